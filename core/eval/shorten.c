/* shorten.c — interval-driven tape shortening (the libfive / fidget technique): over a box,
 * a min or max whose operands' intervals do not overlap always returns the same operand,
 * so the other operand's instructions are dead there. One interval pass records those
 * choices, a backward pass keeps only the instructions the result still needs, and the
 * decided min/max become a copy (or a constant). Register numbers are kept, so the
 * workspace of the original tape serves the shortened one. */
#include "core/eval/shorten.h"
#include "core/eval/interval_eval.h"
#include "core/eval/workspace.h"

#include <assert.h>
#include <math.h>
#include <string.h>

enum { BOTH = 0, ONLY_A = 1, ONLY_B = 2 };

#define KEEP 4u        /* flag bit set in ws->choice[i] when instruction i is kept */
#define CHOICE_MASK 3u

ism_tape *ism_tape_new_like(const ism_tape *t)
{
    if (!t)
        return NULL;
    size_t cap = t->origin_len > t->len ? t->origin_len : t->len;
    ism_tape *out = ism_tape_alloc(cap, t->nregs);
    if (!out)
        return NULL;
    out->result = t->result;
    out->origin_len = cap;
    return out;
}

bool ism_tape_has_min_max(const ism_tape *t)
{
    for (size_t i = 0; i < t->len; i++)
        if (ism_op_is_min_max(t->code[i].op))
            return true;
    return false;
}

bool ism_tape_has_kink(const ism_tape *t)
{
    for (size_t i = 0; i < t->len; i++)
        if (ism_op_is_kink(t->code[i].op))
            return true;
    return false;
}

size_t ism_tape_kinks(const ism_tape *t)
{
    size_t n = 0;
    for (size_t i = 0; i < t->len; i++)
        n += ism_op_is_kink(t->code[i].op);
    return n;
}

ism_piece ism_piece_walk(const ism_tape *t, ism_eval_ws *ws, size_t kinks, bool *open)
{
    uint8_t *needed = ws->needed;
    memset(needed, 0, t->nregs);
    needed[t->result] = 1;
    ism_piece pc = 0;
    size_t k = kinks;
    for (size_t i = t->len; i-- > 0;) {
        const ism_instr *in = &t->code[i];
        bool kink = ism_op_is_kink(in->op);
        k -= kink;
        if (!needed[in->out])
            continue;
        needed[in->out] = 0;
        unsigned br = kink ? ws->choice[i] & CHOICE_MASK : BOTH;
        if (kink && br == BOTH && open)
            *open = true;
        pc |= (ism_piece)br << (2 * k);
        if (ism_op_has_reg_a(in->op) && (br != ONLY_B || in->op == ISM_OP_ABS))
            needed[in->a] = 1; /* abs reads a on both branches */
        if (ism_op_has_reg_b(in->op) && br != ONLY_A)
            needed[in->b] = 1;
    }
    return pc;
}

bool ism_tape_one_piece(const ism_tape *t, ism_eval_ws *ws, ism_interval x, ism_interval y,
                        ism_interval z)
{
    size_t kinks = ism_tape_kinks(t);
    if (!ism_ws_fits(ws, t) || kinks > ISM_PIECE_KINKS)
        return false;
    memset(ws->choice, BOTH, t->len);
    ism_interval_run(t, ws, x, y, z, ws->choice);
    bool open = false;
    ism_piece_walk(t, ws, kinks, &open);
    return !open;
}

bool ism_tape_top_min_max_only(const ism_tape *t)
{
    static const double any[2] = {0, 0};
    if (ism_top_active_branch(t, any) < 0)
        return false;
    for (size_t i = 0; i + 1 < t->len; i++)
        if (ism_op_is_kink(t->code[i].op))
            return false;
    return true;
}

/* The instruction a decided min/max becomes: a copy of the operand it passes on that branch
 * (ism_kink_pass), or its constant. */
static ism_instr decided(const ism_instr *in, unsigned choice)
{
    enum ism_kink_passed pass = ism_kink_pass(in, choice);
    assert(pass != ISM_PASS_NEG_A); /* a shortened tape has no NEG to put here: only min/max
                                      are decided */
    ism_instr r = *in;
    r.b = 0;
    if (pass == ISM_PASS_IMM) {
        r.op = ISM_OP_CONST;
        r.a = 0;
    } else {
        r.op = ISM_OP_COPY;
        r.a = pass == ISM_PASS_B ? in->b : in->a;
        r.imm = 0.0;
    }
    return r;
}

/* Walks backwards from the result, flagging the instructions it still needs given the
 * recorded choices; returns how many are kept. */
static size_t mark_needed(const ism_tape *t, ism_eval_ws *ws)
{
    uint8_t *needed = ws->needed;
    memset(needed, 0, t->nregs);
    needed[t->result] = 1;
    size_t kept = 0;
    for (size_t i = t->len; i-- > 0;) {
        const ism_instr *in = &t->code[i];
        if (!needed[in->out])
            continue;
        ws->choice[i] |= KEEP;
        kept++;
        needed[in->out] = 0;
        unsigned choice = ism_op_is_min_max(in->op) ? ws->choice[i] & CHOICE_MASK : BOTH;
        if (ism_op_has_reg_a(in->op) && choice != ONLY_B)
            needed[in->a] = 1;
        if (ism_op_has_reg_b(in->op) && choice != ONLY_A)
            needed[in->b] = 1;
    }
    return kept;
}

bool ism_tape_shorten(const ism_tape *t, ism_eval_ws *ws, ism_interval x, ism_interval y,
                      ism_interval z, ism_tape *out, ism_interval *range)
{
    ism_interval r;
    bool ran = ism_tape_shorten_pass(t, ws, x, y, z, &r);
    if (range)
        *range = r;
    return ran && ism_tape_shorten_recorded(t, ws, out);
}

bool ism_tape_shorten_pass(const ism_tape *t, ism_eval_ws *ws, ism_interval x, ism_interval y,
                           ism_interval z, ism_interval *range)
{
    if (!ism_ws_fits(ws, t)) {
        *range = (ism_interval){ -INFINITY, INFINITY };
        return false;
    }
    memset(ws->choice, BOTH, t->len);
    *range = ism_interval_run(t, ws, x, y, z, ws->choice);
    return true;
}

const uint8_t *ism_tape_shorten_choices(const ism_eval_ws *ws) { return ws->choice; }

bool ism_tape_shorten_recorded(const ism_tape *t, ism_eval_ws *ws, ism_tape *out)
{
    if (!out || out == t || out->cap < t->len || out->nregs < t->nregs)
        return false;
    if (mark_needed(t, ws) == t->len)
        return false;
    size_t n = 0;
    for (size_t i = 0; i < t->len; i++) {
        if (!(ws->choice[i] & KEEP))
            continue;
        const ism_instr *in = &t->code[i];
        unsigned choice = ism_op_is_min_max(in->op) ? ws->choice[i] & CHOICE_MASK : BOTH;
        out->code[n++] = choice == BOTH ? *in : decided(in, choice);
    }
    out->len = n;
    out->nregs = t->nregs;
    out->result = t->result;
    out->origin_len = t->origin_len > t->len ? t->origin_len : t->len;
    return true;
}
