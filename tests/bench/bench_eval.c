/* bench_eval.c — speed of the expression engine on three surfaces (Kummer in let form,
 * the figure-8 Klein bottle, Barth's sextic): evaluations per second of the batched double
 * evaluator, the interval evaluator and, as the in-process reference, a plain recursive
 * walk of the syntax tree (the tape expanded back into a tree: every sub-expression its
 * own node, as a parser would build it). Also times the outward-rounding primitive against
 * nextafter(). bench_eval.py runs this beside the same formulas written in C and compiled
 * with gcc -O2, and prints the table.
 *
 * Output: one line per figure, "SURFACE KIND VALUE" (evaluations per second), plus
 * "SURFACE checksum VALUE" (sum of f over the points, to check that both agree). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "core/eval/eval.h"
#include "core/expr/tape.h"
#include "core/util/clock.h"

#define NPOINTS (1u << 16)
#define NBOXES 4096
#define MIN_SECONDS 0.3

typedef struct surface {
    const char *name;
    const char *expr;
    ism_param params[4];
    size_t nparams;
    ism_let lets[6];
    size_t nlets;
    double half;   /* the box is [-half, half]^3 */
} surface;

static const surface SURFACES[] = {
    { "kummer", "(x^2 + y^2 + z^2 - mu2)^2 - lambda*p*q*r*s", { { "mu2", 0.6667 }, { "w", 1 } },
      2,
      { { "lambda", "(3*mu2 - 1)/(3 - mu2)" }, { "p", "w - z - sqrt(2)*x" },
        { "q", "w - z + sqrt(2)*x" }, { "r", "w + z + sqrt(2)*y" },
        { "s", "w + z - sqrt(2)*y" } },
      5, 3.0 },
    { "klein", "(x^2 + y^2 + z^2 + 2*y - 1)*((x^2 + y^2 + z^2 - 2*y - 1)^2 - 8*z^2) + "
               "16*x*z*(x^2 + y^2 + z^2 - 2*y - 1)",
      { { 0 } }, 0, { { 0 } }, 0, 4.0 },
    { "barth6", "4*(phi^2*x^2 - y^2)*(phi^2*y^2 - z^2)*(phi^2*z^2 - x^2) - "
                "(1 + 2*phi)*(x^2 + y^2 + z^2 - 1)^2",
      { { "phi", 1.6180339887498949 } }, 1, { { 0 } }, 0, 2.0 },
};

/* The same point generator as the generated C reference (bench_eval.py). */
static double next_unit(unsigned long long *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*s >> 11) * 0x1p-53;
}

/* ---- the syntax-tree walker (reference) ---- */

typedef struct tnode {
    int op;            /* tape opcode, or -1 - k for input k */
    double imm;
    unsigned n;
    struct tnode *a, *b;
} tnode;

static tnode *tree_of(const ism_tape *t, size_t i);

/* Builds the tree for register r as read by instruction i. */
static tnode *operand_tree(const ism_tape *t, uint32_t r, size_t i)
{
    if (r < ISM_FIRST_FREE_REG) {
        tnode *n = calloc(1, sizeof *n);
        n->op = -1 - (int)r;
        return n;
    }
    /* the last instruction before i that wrote r */
    size_t j = i;
    while (j-- > 0)
        if (t->code[j].out == r)
            break;
    return tree_of(t, j);
}

static tnode *tree_of(const ism_tape *t, size_t i)
{
    const ism_instr *in = &t->code[i];
    tnode *n = calloc(1, sizeof *n);
    n->op = in->op;
    n->imm = in->imm;
    n->n = in->b;
    if (ism_op_has_reg_a(in->op))
        n->a = operand_tree(t, in->a, i);
    if (ism_op_has_reg_b(in->op))
        n->b = operand_tree(t, in->b, i);
    return n;
}

static double walk(const tnode *n, double x, double y, double z)
{
    switch (n->op) {
    case -1: return x;
    case -2: return y;
    case -3: return z;
    case ISM_OP_CONST: return n->imm;
    case ISM_OP_ADD_RR: return walk(n->a, x, y, z) + walk(n->b, x, y, z);
    case ISM_OP_ADD_RC: return walk(n->a, x, y, z) + n->imm;
    case ISM_OP_SUB_RR: return walk(n->a, x, y, z) - walk(n->b, x, y, z);
    case ISM_OP_SUB_CR: return n->imm - walk(n->a, x, y, z);
    case ISM_OP_MUL_RR: return walk(n->a, x, y, z) * walk(n->b, x, y, z);
    case ISM_OP_MUL_RC: return walk(n->a, x, y, z) * n->imm;
    case ISM_OP_DIV_RR: return walk(n->a, x, y, z) / walk(n->b, x, y, z);
    case ISM_OP_DIV_RC: return walk(n->a, x, y, z) / n->imm;
    case ISM_OP_DIV_CR: return n->imm / walk(n->a, x, y, z);
    case ISM_OP_NEG: return -walk(n->a, x, y, z);
    case ISM_OP_SQUARE: { double v = walk(n->a, x, y, z); return v * v; }
    case ISM_OP_POWI: return pow(walk(n->a, x, y, z), n->n);
    case ISM_OP_SQRT: return sqrt(walk(n->a, x, y, z));
    default: return NAN; /* the bench surfaces use nothing else */
    }
}

static void free_tree(tnode *n)
{
    if (!n)
        return;
    free_tree(n->a);
    free_tree(n->b);
    free(n);
}

/* ---- timing ---- */

typedef struct points {
    double *x, *y, *z, *out;
} points;

static double time_batch(const ism_tape *t, ism_eval_ws *ws, const points *p, double *sum)
{
    double best = 0.0;
    for (int run = 0; run < 3; run++) {
        size_t evals = 0;
        double t0 = ism_now_s(), t1;
        do {
            ism_eval_batch(t, ws, p->x, p->y, p->z, p->out, NPOINTS);
            evals += NPOINTS;
        } while ((t1 = ism_now_s()) - t0 < MIN_SECONDS);
        best = fmax(best, evals / (t1 - t0));
    }
    *sum = 0.0;
    for (size_t i = 0; i < NPOINTS; i++)
        *sum += p->out[i];
    return best;
}

static double time_tree(const tnode *root, const points *p)
{
    double best = 0.0;
    for (int run = 0; run < 3; run++) {
        size_t evals = 0;
        double t0 = ism_now_s(), t1;
        do {
            for (size_t i = 0; i < NPOINTS; i++)
                p->out[i] = walk(root, p->x[i], p->y[i], p->z[i]);
            evals += NPOINTS;
        } while ((t1 = ism_now_s()) - t0 < MIN_SECONDS);
        best = fmax(best, evals / (t1 - t0));
    }
    return best;
}

/* Boxes as an octree visits them: sides half^1 .. half/2^8 at random places. */
static double time_interval(const ism_tape *t, ism_eval_ws *ws, double half, double *width)
{
    static ism_interval boxes[NBOXES][3];
    unsigned long long s = 12345;
    for (int b = 0; b < NBOXES; b++) {
        double side = 2.0 * half / (double)(1u << (b % 9));
        for (int k = 0; k < 3; k++) {
            double lo = -half + (2.0 * half - side) * next_unit(&s);
            boxes[b][k] = (ism_interval){ lo, lo + side };
        }
    }
    double best = 0.0, acc = 0.0;
    for (int run = 0; run < 3; run++) {
        size_t evals = 0;
        double t0 = ism_now_s(), t1;
        do {
            for (int b = 0; b < NBOXES; b++) {
                ism_interval r = ism_eval_interval(t, ws, boxes[b][0], boxes[b][1], boxes[b][2]);
                __asm__ volatile("" : : "x"(r.lo), "x"(r.hi));
            }
            evals += NBOXES;
        } while ((t1 = ism_now_s()) - t0 < MIN_SECONDS);
        best = fmax(best, evals / (t1 - t0));
    }
    for (int b = 0; b < NBOXES; b++) {
        ism_interval r = ism_eval_interval(t, ws, boxes[b][0], boxes[b][1], boxes[b][2]);
        acc += r.hi - r.lo;
    }
    *width = acc;
    return best;
}

/* The same boxes through the batched interval evaluator. */
static double time_interval_batch(const ism_tape *t, ism_eval_ws *ws, double half, double *width)
{
    static ism_interval bx[NBOXES], by[NBOXES], bz[NBOXES], out[NBOXES];
    unsigned long long s = 12345;
    for (int b = 0; b < NBOXES; b++) {
        double side = 2.0 * half / (double)(1u << (b % 9));
        ism_interval *dst[3] = { &bx[b], &by[b], &bz[b] };
        for (int k = 0; k < 3; k++) {
            double lo = -half + (2.0 * half - side) * next_unit(&s);
            *dst[k] = (ism_interval){ lo, lo + side };
        }
    }
    double best = 0.0, acc = 0.0;
    for (int run = 0; run < 3; run++) {
        size_t evals = 0;
        double t0 = ism_now_s(), t1;
        do {
            ism_eval_interval_batch(t, ws, bx, by, bz, out, NBOXES);
            evals += NBOXES;
        } while ((t1 = ism_now_s()) - t0 < MIN_SECONDS);
        best = fmax(best, evals / (t1 - t0));
    }
    for (int b = 0; b < NBOXES; b++)
        acc += out[b].hi - out[b].lo;
    *width = acc;
    return best;
}

/* Outward rounding: the arithmetic widening the interval evaluator uses vs nextafter. */
static void time_rounding(void)
{
    enum { N = 4096 };
    static double v[N], o[N];
    unsigned long long s = 99;
    for (int i = 0; i < N; i++)
        v[i] = (next_unit(&s) - 0.5) * 1e3;
    double best_w = 0.0, best_n = 0.0;
    for (int run = 0; run < 3; run++) {
        size_t ops = 0;
        double t0 = ism_now_s(), t1;
        do {
            for (int i = 0; i < N; i++)
                o[i] = v[i] - (fabs(v[i]) * 0x1p-52 + 0x1p-1074);
            ops += N;
            __asm__ volatile("" : : "r"(o) : "memory");
        } while ((t1 = ism_now_s()) - t0 < 0.1);
        best_w = fmax(best_w, ops / (t1 - t0));
        ops = 0;
        t0 = ism_now_s();
        do {
            for (int i = 0; i < N; i++)
                o[i] = nextafter(v[i], -INFINITY);
            ops += N;
            __asm__ volatile("" : : "r"(o) : "memory");
        } while ((t1 = ism_now_s()) - t0 < 0.1);
        best_n = fmax(best_n, ops / (t1 - t0));
    }
    printf("rounding widen %.6g\nrounding nextafter %.6g\n", best_w, best_n);
}

int main(void)
{
    points p = { malloc(NPOINTS * sizeof(double)), malloc(NPOINTS * sizeof(double)),
                 malloc(NPOINTS * sizeof(double)), malloc(NPOINTS * sizeof(double)) };
    if (!p.x || !p.y || !p.z || !p.out)
        return 1;
    for (size_t s = 0; s < sizeof SURFACES / sizeof SURFACES[0]; s++) {
        const surface *sf = &SURFACES[s];
        ism_error err;
        char msg[256];
        ism_tape *t = ism_tape_compile(sf->expr, sf->params, sf->nparams, sf->lets, sf->nlets,
                                       NULL, &err);
        if (!t) {
            fprintf(stderr, "%s: %s\n", sf->name, ism_error_format(&err, msg, sizeof msg));
            return 1;
        }
        ism_eval_ws *ws = ism_eval_ws_new(t);
        unsigned long long seed = 2024;
        for (size_t i = 0; i < NPOINTS; i++) {
            p.x[i] = sf->half * (2.0 * next_unit(&seed) - 1.0);
            p.y[i] = sf->half * (2.0 * next_unit(&seed) - 1.0);
            p.z[i] = sf->half * (2.0 * next_unit(&seed) - 1.0);
        }
        double sum, width;
        printf("%s tape %zu\n", sf->name, ism_tape_length(t));
        printf("%s batch %.6g\n", sf->name, time_batch(t, ws, &p, &sum));
        printf("%s checksum %.17g\n", sf->name, sum);
        double width_batch;
        printf("%s interval %.6g\n", sf->name, time_interval(t, ws, sf->half, &width));
        printf("%s ivbatch %.6g\n", sf->name,
               time_interval_batch(t, ws, sf->half, &width_batch));
        /* The batch rounds each bound correctly outward, the single box by one ulp more. */
        printf("%s ivtighter %d\n", sf->name, width_batch <= width);
        tnode *root = tree_of(t, t->len - 1);
        printf("%s tree %.6g\n", sf->name, time_tree(root, &p));
        fflush(stdout);
        free_tree(root);
        ism_eval_ws_free(ws);
        ism_tape_free(t);
    }
    time_rounding();
    free(p.x);
    free(p.y);
    free(p.z);
    free(p.out);
    return 0;
}
