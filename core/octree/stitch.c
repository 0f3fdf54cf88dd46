/* stitch.c — StitchPolygon (paper §3): joins a node's face lines into closed polygons.
 * End points match exactly (every node computes a shared point bit for bit the same), so
 * the lines form a graph; where more than two line ends meet (two sheets through one point)
 * they are paired so that a polygon never turns from one sheet onto the other:
 *   - a line of one polygon pairs first with a copy of a line shared by two polygons
 *     (`nonManLine`: a double line on the face or a zero edge);
 *   - two lines of single polygons pair when the gradients at their far ends agree most;
 *   - leftover shared copies pair with each other: a one-edge (degenerate) polygon.
 * Then each polygon is walked once. Up to two polygons per node are the paper's cases; more
 * are kept and counted. */
#include "core/octree/stitch.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct end_ref {
    double p[3];
    int end; /* 2 * line + (0 for a, 1 for b) */
} end_ref;

static int cmp_end(const void *x, const void *y)
{
    const end_ref *a = x, *b = y;
    for (int k = 0; k < 3; k++) {
        if (a->p[k] < b->p[k])
            return -1;
        if (a->p[k] > b->p[k])
            return 1;
    }
    return (a->end > b->end) - (a->end < b->end);
}

static const ism_fpoint *end_point(const ism_flines *l, int end)
{
    const ism_fline *ln = &l->v[end >> 1];
    return end & 1 ? &ln->b : &ln->a;
}

static bool is_shared(const ism_flines *l, int end)
{
    return l->v[end >> 1].kind != ISM_LINE_REGULAR;
}

static double far_agreement(const ism_flines *l, int e1, int e2)
{
    const double *g1 = end_point(l, e1 ^ 1)->g, *g2 = end_point(l, e2 ^ 1)->g;
    double n1 = ism_norm3(g1), n2 = ism_norm3(g2);
    if (!(n1 > 0) || !(n2 > 0))
        return 0;
    return fabs(ism_dot3(g1, g2)) / (n1 * n2);
}

/* Pairs the line ends meeting at one point (partner[] gets each end's mate, or -1). */
static void pair_node(const ism_flines *l, const end_ref *group, int n, int *partner)
{
    int reg[64], shr[64], nr = 0, ns = 0;
    for (int i = 0; i < n && i < 64; i++) {
        if (is_shared(l, group[i].end))
            shr[ns++] = group[i].end;
        else
            reg[nr++] = group[i].end;
    }
    int r = 0, s = 0;
    if (n == 2) {
        partner[group[0].end] = group[1].end;
        partner[group[1].end] = group[0].end;
        return;
    }
    for (; r < nr && s < ns; r++, s++) {
        partner[reg[r]] = shr[s];
        partner[shr[s]] = reg[r];
    }
    /* remaining single-polygon lines: greedy by agreement of their far-end gradients */
    bool used[64] = {false};
    for (int i = r; i < nr; i++) {
        if (used[i])
            continue;
        int best = -1;
        double best_a = -1;
        for (int j = i + 1; j < nr; j++) {
            if (used[j])
                continue;
            double a = far_agreement(l, reg[i], reg[j]);
            if (a > best_a)
                best_a = a, best = j;
        }
        used[i] = true;
        if (best >= 0) {
            used[best] = true;
            partner[reg[i]] = reg[best];
            partner[reg[best]] = reg[i];
        }
    }
    for (; s + 1 < ns; s += 2) {
        partner[shr[s]] = shr[s + 1];
        partner[shr[s + 1]] = shr[s];
    }
}

static bool push_loop_point(ism_loops *out, const ism_fpoint *p)
{
    if (out->npts == out->cap_pts) {
        size_t c = out->cap_pts ? out->cap_pts * 2 : 64;
        ism_fpoint *v = realloc(out->pts, c * sizeof *v);
        if (!v)
            return false;
        out->pts = v;
        out->cap_pts = c;
    }
    out->pts[out->npts++] = *p;
    return true;
}

static bool close_loop(ism_loops *out, size_t start, bool closed)
{
    if (out->nloops == out->cap_loops) {
        size_t c = out->cap_loops ? out->cap_loops * 2 : 8;
        ism_loop *v = realloc(out->loops, c * sizeof *v);
        if (!v)
            return false;
        out->loops = v;
        out->cap_loops = c;
    }
    out->loops[out->nloops++] = (ism_loop){start, out->npts - start, closed};
    return true;
}

/* Walks from end e0 along lines and pairings until the walk returns or dead-ends. */
static bool walk(const ism_flines *l, const int *partner, bool *used, int e0, ism_loops *out)
{
    size_t start = out->npts;
    int e = e0;
    if (!push_loop_point(out, end_point(l, e)))
        return false;
    for (;;) {
        used[e >> 1] = true;
        int o = e ^ 1;
        int p = partner[o];
        if (p == e0)
            return close_loop(out, start, true);
        if (!push_loop_point(out, end_point(l, o)))
            return false;
        if (p < 0 || used[p >> 1])
            return close_loop(out, start, false);
        e = p;
    }
}

bool ism_stitch(const ism_flines *l, ism_loops *out)
{
    out->npts = out->nloops = 0;
    size_t ne = 2 * l->n;
    if (ne == 0)
        return true;
    end_ref *refs = malloc(ne * sizeof *refs);
    int *partner = malloc(ne * sizeof *partner);
    bool *used = calloc(l->n, sizeof *used);
    bool ok = refs && partner && used;
    if (!ok)
        goto done;
    for (size_t e = 0; e < ne; e++) {
        memcpy(refs[e].p, end_point(l, (int)e)->p, sizeof refs[e].p);
        refs[e].end = (int)e;
        partner[e] = -1;
    }
    qsort(refs, ne, sizeof *refs, cmp_end);
    for (size_t i = 0; i < ne;) {
        size_t j = i + 1;
        while (j < ne && memcmp(refs[j].p, refs[i].p, sizeof refs[i].p) == 0)
            j++;
        pair_node(l, refs + i, (int)(j - i), partner);
        i = j;
    }
    /* open chains first, from a dangling end, so each is walked whole */
    for (size_t e = 0; e < ne && ok; e++)
        if (partner[e] < 0 && !used[e >> 1])
            ok = walk(l, partner, used, (int)e, out);
    for (size_t k = 0; k < l->n && ok; k++)
        if (!used[k])
            ok = walk(l, partner, used, (int)(2 * k), out);
done:
    free(refs);
    free(partner);
    free(used);
    return ok;
}

void ism_loops_free(ism_loops *o)
{
    free(o->pts);
    free(o->loops);
    memset(o, 0, sizeof *o);
}
