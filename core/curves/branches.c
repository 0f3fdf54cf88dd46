/* branches.c — numbering the branches of f: at a point, f's tape is shortened over the
 * point's degenerate box (every min/max whose operands differ there becomes a copy of the
 * larger or smaller one, dead instructions dropped), and the shortened tape compared with
 * the branches seen so far, instruction by instruction. */
#include "core/curves/branches.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/eval/eval.h"
#include "core/expr/tape.h"

bool ism_branches_any(const ism_tape *f)
{
    return ism_tape_has_min_max(f);
}

bool ism_branches_init(ism_branches *b, const ism_tape *f)
{
    memset(b, 0, sizeof *b);
    b->f = f;
    b->fws = ism_eval_ws_new(f);
    b->scratch = ism_tape_new_like(f);
    if (!b->fws || !b->scratch) {
        ism_branches_free(b);
        return false;
    }
    return true;
}

void ism_branches_free(ism_branches *b)
{
    ism_eval_ws_free(b->fws);
    ism_tape_free(b->scratch);
    for (size_t i = 0; i < b->n; i++) {
        ism_tape_free(b->tape[i]);
        ism_eval_ws_free(b->ws[i]);
    }
    for (size_t i = 0; i < b->nev; i++)
        if (b->ev[i]) {
            ism_cut_eval_free(b->ev[i]);
            free(b->ev[i]);
        }
    memset(b, 0, sizeof *b);
}

static bool same_code(const ism_tape *x, const ism_tape *y)
{
    if (x->len != y->len || x->result != y->result)
        return false;
    for (size_t i = 0; i < x->len; i++) {
        const ism_instr *a = &x->code[i], *c = &y->code[i];
        if (a->op != c->op || a->out != c->out || a->a != c->a || a->b != c->b ||
            memcmp(&a->imm, &c->imm, sizeof a->imm))
            return false;
    }
    return true;
}

bool ism_branches_at(ism_branches *b, const double p[3], uint32_t *id)
{
    return ism_branches_in_box(b, p, p, id);
}

bool ism_branches_in_box(ism_branches *b, const double lo[3], const double hi[3], uint32_t *id)
{
    *id = ISM_BRANCH_NONE;
    ism_interval x = {lo[0], hi[0]}, y = {lo[1], hi[1]}, z = {lo[2], hi[2]};
    if (!ism_tape_shorten(b->f, b->fws, x, y, z, b->scratch, NULL))
        return true; /* nothing decided: no min/max, or a tie */
    const ism_tape *t = b->scratch;
    if (ism_branches_any(t))
        return true; /* a min/max still open: a tie at p */
    for (size_t i = 0; i < b->n; i++)
        if (same_code(t, b->tape[i])) {
            *id = (uint32_t)i;
            return true;
        }
    if (b->n == ISM_BRANCH_MAX)
        return true;
    ism_tape *copy = ism_tape_alloc(t->len ? t->len : 1, t->nregs);
    if (!copy)
        return false;
    copy->len = t->len;
    copy->result = t->result;
    memcpy(copy->code, t->code, t->len * sizeof t->code[0]);
    ism_eval_ws *ws = ism_eval_ws_new(copy);
    if (!ws) {
        ism_tape_free(copy);
        return false;
    }
    b->tape[b->n] = copy;
    b->ws[b->n] = ws;
    b->fn[b->n] = (ism_cut_fn){.tape = copy, .kind = ISM_CUT_INTERSECTION, .source = -1};
    *id = (uint32_t)b->n++;
    return true;
}

double ism_branches_gradient(ism_branches *b, uint32_t i, const double p[3], double grad[3])
{
    return ism_eval_gradient(b->tape[i], b->ws[i], p[0], p[1], p[2], grad);
}

void ism_branches_project(ism_branches *b, uint32_t i, int steps, double tol, double p[3])
{
    for (int it = 0; it < steps; it++) {
        double g[3], f = ism_branches_gradient(b, i, p, g), gg = g[0] * g[0] + g[1] * g[1] +
                                                              g[2] * g[2];
        if (!(gg > 0) || !isfinite(f) || f * f <= tol * tol * gg)
            break;
        for (int c = 0; c < 3; c++)
            p[c] -= f * g[c] / gg;
    }
}

bool ism_branches_refine(ism_branches *b, uint32_t a, const size_t *ks, int nk,
                         const double plane[4], double tol, double max_move, double p[3])
{
    if (a >= b->n || nk > 2 || (plane && nk > 1))
        return false;
    for (int i = 0; i < nk; i++)
        if (ks[i] >= b->n)
            return false;
    if (b->nev < b->n) { /* the evaluations made for fewer branches are stale */
        for (size_t i = 0; i < b->nev; i++)
            if (b->ev[i]) {
                ism_cut_eval_free(b->ev[i]);
                free(b->ev[i]);
                b->ev[i] = NULL;
            }
        b->nev = b->n;
    }
    if (!b->ev[a]) {
        ism_cut_eval *ev = malloc(sizeof *ev);
        if (!ev || !ism_cut_eval_init(ev, b->tape[a], b->fn, b->n + 1)) {
            free(ev);
            return false;
        }
        b->ev[a] = ev;
    }
    size_t k2[2] = {ks[0], nk > 1 ? ks[1] : b->n};
    if (plane) {
        b->fn[b->n] = (ism_cut_fn){.n = {plane[0], plane[1], plane[2]}, .c = plane[3],
                                   .kind = ISM_CUT_SECTION, .source = -1};
        nk++;
    }
    return ism_cut_refine(b->ev[a], k2, nk, tol, max_move, p);
}
