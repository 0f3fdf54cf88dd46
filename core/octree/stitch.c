/* stitch.c — StitchPolygon (paper §3): joins a node's face lines into closed polygons.
 * End points match exactly (every node computes a shared point bit for bit the same), so
 * the lines form a graph. As in the paper, the lines of single polygons (`line`) are chained
 * first, and a chain is closed by lines shared by two polygons (`nonManLine`: double lines on
 * a face, zero edges) joining its two ends, so each sheet through a self-intersection gets
 * its own polygon:
 *   - a point with shared lines ends the chains that reach it;
 *   - elsewhere, where more than two single-polygon lines meet (two sheets through one
 *     point), they pair so that the gradients at their far ends agree most;
 *   - a chain is closed by a path of unused shared lines between its ends (one copy each);
 *   - shared lines left over are one-edge (degenerate) polygons.
 * Up to two polygons per node are the paper's cases; more are kept and counted. */
#include "core/octree/stitch.h"
#include "core/octree/sampler.h"
#include "core/util/grow.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A node has a handful of lines (a plain polygon: 3 to 6, 2 ends each; a few more where
 * sheets cross), so its line ends are few. Up to FEW_ENDS ends the graph lives on
 * ism_stitch's stack (no allocation per leaf) and the ends are grouped by their points
 * without a sort (grouped_ends; a NaN coordinate is sorted, as more ends are); more ends
 * are allocated and qsorted. The Klein bottle at E = 3.27e-3 stitches 39,768 leaves, none
 * with more (callgrind line counts of the allocating branch). */
#define FEW_ENDS 32

typedef struct end_ref {
    double p[3];
    int end; /* 2 * line + (0 for a, 1 for b) */
} end_ref;

typedef struct graph {
    const ism_flines *l;
    bool plain;     /* plain_pairs: every end paired, no terminal point (node unset) */
    int *node;      /* per end: its point's index */
    int *partner;   /* per end: the single-polygon end it continues into, or -1 */
    bool *terminal; /* per point: some shared line ends here */
    bool *used;     /* per line */
    int npoints;
    bool heap;      /* the four arrays were allocated (else they are the ones below) */
    int node_in[FEW_ENDS], partner_in[FEW_ENDS];
    bool terminal_in[FEW_ENDS], used_in[FEW_ENDS / 2];
} graph;

/* Coordinates by value (-0 equal to 0), NaN after every number and NaNs by their bits: a
 * total order, which qsort needs (NaN compared by value alone is neither below, above nor
 * equal, and a sort given such an order may leave anything), and in which ends whose
 * points are the same bits are always equal. */
static int cmp_coord(double a, double b)
{
    if (a < b)
        return -1;
    if (a > b)
        return 1;
    if (a == b)
        return 0;
    bool na = a != a, nb = b != b;
    if (na != nb)
        return na ? 1 : -1;
    uint64_t ua, ub;
    memcpy(&ua, &a, sizeof ua);
    memcpy(&ub, &b, sizeof ub);
    return (ua > ub) - (ua < ub);
}

static int cmp_end(const void *x, const void *y)
{
    const end_ref *a = x, *b = y;
    for (int k = 0; k < 3; k++) {
        int c = cmp_coord(a->p[k], b->p[k]);
        if (c)
            return c;
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

/* Pairs the single-polygon ends meeting at a point without shared lines (group[0 .. n), in
 * ascending order): each end, in order, with the later unpaired end whose far gradient
 * agrees most. Any number of ends (an end is unpaired while its partner is -1, as
 * build_graph set it; it used to stop at 64 ends, which a node never reaches: at most 3
 * faces x 4 tiles meet at a point, each tile giving it at most 2 lines). An end left
 * without a partner starts an open chain. */
static void pair_point(graph *g, const int *group, int n)
{
    for (int i = 0; i < n; i++) {
        int ei = group[i];
        if (g->partner[ei] >= 0)
            continue;
        int best = -1;
        double best_a = -1;
        for (int j = i + 1; j < n; j++) {
            int ej = group[j];
            if (g->partner[ej] >= 0)
                continue;
            double a = far_agreement(g->l, ei, ej);
            if (a > best_a)
                best_a = a, best = ej;
        }
        if (best >= 0) {
            g->partner[ei] = best;
            g->partner[best] = ei;
        }
    }
}

/* The ends sorted by cmp_end (points compared by value, -0 equal to 0, then by end) into
 * order[0 .. ne); up to FEW_ENDS sorted on the stack. cmp_end is a total order and no two
 * ends are equal in it, so the sorted order is the one any sort leaves. */
static bool sorted_ends(const ism_flines *l, size_t ne, int *order)
{
    end_ref refs_in[FEW_ENDS], *refs = refs_in;
    if (ne > FEW_ENDS && !(refs = malloc(ne * sizeof *refs)))
        return false;
    for (size_t e = 0; e < ne; e++) {
        memcpy(refs[e].p, end_point(l, (int)e)->p, sizeof refs[e].p);
        refs[e].end = (int)e;
    }
    qsort(refs, ne, sizeof *refs, cmp_end);
    for (size_t e = 0; e < ne; e++)
        order[e] = refs[e].end;
    if (refs != refs_in)
        free(refs);
    return true;
}

static bool has_nan(const double p[3])
{
    return p[0] != p[0] || p[1] != p[1] || p[2] != p[2];
}

/* The few ends (ne ≤ FEW_ENDS) into order[0 .. ne), their points into at[0 .. ne), by the
 * points' values, ends ascending among equal values: the points in the order each first
 * appears, where cmp_end's sort puts them in coordinate order. Only where the ends meet is
 * read (build_graph groups the ends of one point, and what a group does never depends on
 * the others'), and a group's ends keep cmp_end's order, -0 and 0 interleaved by end as it
 * leaves them. False when a coordinate is NaN (equal to nothing by value, where cmp_end
 * groups NaNs by their bits): the caller sorts. */
static bool grouped_ends(const ism_flines *l, size_t ne, int *order, const ism_fpoint **at)
{
    const ism_fpoint *ep[FEW_ENDS];
    const double *rep[FEW_ENDS]; /* each distinct value's first point */
    int cls[FEW_ENDS], count[FEW_ENDS + 1] = {0}, nc = 0;
    for (size_t e = 0; e < ne; e++) {
        ep[e] = end_point(l, (int)e);
        const double *p = ep[e]->p;
        int c = 0;
        while (c < nc && !(rep[c][0] == p[0] && rep[c][1] == p[1] && rep[c][2] == p[2]))
            c++;
        if (c == nc) { /* a NaN point equals none: it starts a value of its own */
            if (has_nan(p))
                return false;
            rep[nc++] = p;
        }
        cls[e] = c;
        count[c + 1]++;
    }
    for (int c = 0; c < nc; c++)
        count[c + 1] += count[c];
    for (size_t e = 0; e < ne; e++) {
        int k = count[cls[e]]++;
        order[k] = (int)e;
        at[k] = ep[e];
    }
    return true;
}

/* Is far_agreement of two ends whose far gradients are g1, g2 a number (so pair_point
 * pairs them), known without working it out? Squared norms within 2^±900 keep the norms,
 * their product and the dot product finite and the product nonzero. Sufficient, not tight:
 * a false only costs a far_agreement. */
static bool agreement_a_number(const double g1[3], const double g2[3])
{
    double s1 = ism_dot3(g1, g1), s2 = ism_dot3(g2, g2);
    return s1 > 0x1p-900 && s1 < 0x1p900 && s2 > 0x1p-900 && s2 < 0x1p900;
}

/* The common node on the stack (ne ≤ FEW_ENDS): single-polygon lines only, whose ends meet
 * two by two, each two the same bits, neither singular, their far gradients' agreement a
 * number. The graph is then the general one's without a sort or a grouping: each point is
 * a group of two ends, pair_point pairs them (the agreement > -1), and no point is terminal;
 * so no chain starts at an end and every loop is closed (ism_stitch's second loop alone).
 * False (partner possibly written) when the node is not so: the caller builds the general
 * graph. The Klein bottle at E = 3.27e-3: every stitched leaf but a few (callgrind). */
static bool plain_pairs(graph *g, const ism_flines *l, size_t ne)
{
    const ism_fpoint *ep[FEW_ENDS];
    for (size_t k = 0; k < l->n; k++) {
        if (l->v[k].kind != ISM_LINE_REGULAR)
            return false;
        ep[2 * k] = &l->v[k].a;
        ep[2 * k + 1] = &l->v[k].b;
    }
    for (size_t e = 0; e < ne; e++)
        g->partner[e] = -1;
    for (size_t e = 0; e < ne; e++) {
        if (g->partner[e] >= 0)
            continue;
        const double *p = ep[e]->p;
        size_t f = ne;
        for (size_t j = e + 1; j < ne; j++) { /* a NaN coordinate equals none: no partner */
            const double *q = ep[j]->p;
            if (q[0] == p[0] && q[1] == p[1] && q[2] == p[2]) {
                if (f < ne)
                    return false; /* three ends or more at one point */
                f = j;
            }
        }
        if (f == ne || memcmp(ep[f]->p, p, 3 * sizeof *p) != 0 ||
            ((ep[e]->flags | ep[f]->flags) & ISM_FP_SINGULAR) ||
            !(agreement_a_number(ep[e ^ 1]->g, ep[f ^ 1]->g) ||
              far_agreement(l, (int)e, (int)f) > -1))
            return false;
        g->partner[e] = (int)f;
        g->partner[f] = (int)e;
    }
    return true;
}

/* Sets g->heap and the four arrays first (allocated ones possibly NULL), so free_graph may
 * run whatever this returns. */
static bool build_graph(graph *g, const ism_flines *l)
{
    size_t ne = 2 * l->n;
    int order_in[FEW_ENDS], *order = order_in;
    const ism_fpoint *at_in[FEW_ENDS], **at = at_in; /* the ends' points, in order */
    g->l = l;
    g->plain = false;
    g->heap = ne > FEW_ENDS;
    if (g->heap) {
        order = malloc(ne * sizeof *order);
        at = malloc(ne * sizeof *at);
        g->node = malloc(ne * sizeof *g->node);
        g->partner = malloc(ne * sizeof *g->partner);
        g->terminal = calloc(ne, sizeof *g->terminal);
        g->used = calloc(l->n, sizeof *g->used);
        if (!order || !at || !g->node || !g->partner || !g->terminal || !g->used) {
            free(order);
            free(at);
            return false; /* the caller's free_graph frees the others */
        }
    } else {
        g->node = g->node_in;
        g->partner = g->partner_in;
        g->terminal = g->terminal_in;
        g->used = memset(g->used_in, 0, l->n * sizeof *g->used);
        if ((g->plain = plain_pairs(g, l, ne)))
            return true;
        memset(g->terminal_in, 0, ne * sizeof *g->terminal);
    }
    for (size_t e = 0; e < ne; e++)
        g->partner[e] = -1;
    bool ordered = !g->heap && grouped_ends(l, ne, order, at);
    if (!ordered && !sorted_ends(l, ne, order)) {
        if (order != order_in)
            free(order), free(at);
        return false;
    }
    for (size_t i = 0; !ordered && i < ne; i++)
        at[i] = end_point(l, order[i]);
    /* a point: a run of ends whose points are the same bits (cmp_end's order puts -0 and 0
     * together, which this parts again) */
    g->npoints = 0;
    for (size_t i = 0; i < ne;) {
        const double *p = at[i]->p;
        size_t j = i + 1;
        while (j < ne && memcmp(at[j]->p, p, 3 * sizeof *p) == 0)
            j++;
        int pt = g->npoints++;
        bool shared = false;
        for (size_t k = i; k < j; k++) {
            g->node[order[k]] = pt;
            shared |= is_shared(l, order[k]);
            /* a singular point ends chains too: each sheet's polygon passes it once */
            shared |= (at[k]->flags & ISM_FP_SINGULAR) != 0;
        }
        g->terminal[pt] = shared;
        if (!shared)
            pair_point(g, order + i, (int)(j - i));
        i = j;
    }
    if (order != order_in)
        free(order), free(at);
    return true;
}

static void free_graph(graph *g)
{
    if (!g->heap)
        return;
    free(g->node);
    free(g->partner);
    free(g->terminal);
    free(g->used);
}

static bool push_loop_point(ism_loops *out, const ism_fpoint *p)
{
    if (!ism_grow((void **)&out->pts, &out->cap_pts, out->npts + 1, sizeof *out->pts, 64))
        return false;
    out->pts[out->npts++] = *p;
    return true;
}

static bool close_loop(ism_loops *out, size_t start, bool closed)
{
    if (!ism_grow((void **)&out->loops, &out->cap_loops, out->nloops + 1, sizeof *out->loops, 8))
        return false;
    out->loops[out->nloops++] = (ism_loop){start, out->npts - start, closed};
    return true;
}

/* Walks single-polygon lines from end e0 until the walk returns to e0 (*closed) or stops at
 * a terminal point or a dangling end; appends the points; returns the last end reached. */
static int walk_chain(graph *g, int e0, ism_loops *out, bool *closed, bool *ok)
{
    int e = e0;
    *closed = false;
    *ok = push_loop_point(out, end_point(g->l, e));
    for (;;) {
        g->used[e >> 1] = true;
        int o = e ^ 1;
        int p = g->partner[o];
        if (p == e0) {
            *closed = true;
            return o;
        }
        if (!(*ok = *ok && push_loop_point(out, end_point(g->l, o))))
            return o;
        if (p < 0 || g->used[p >> 1])
            return o;
        e = p;
    }
}

/* Finds a path of unused shared lines from point `from` to point `to` (breadth first);
 * marks them used and appends the inner points; false when there is none. */
static bool close_with_shared(graph *g, int from, int to, ism_loops *out, bool *ok)
{
    if (from == to)
        return true;
    size_t nl = g->l->n;
    int via_in[FEW_ENDS], queue_in[FEW_ENDS], *via = via_in, *queue = queue_in;
    if (g->npoints > FEW_ENDS) { /* a point has an end: npoints ≤ ends, FEW_ENDS on the stack */
        via = malloc((size_t)g->npoints * sizeof *via); /* end used to reach each point */
        queue = malloc((size_t)g->npoints * sizeof *queue);
    }
    if (!via || !queue) {
        if (via != via_in)
            free(via), free(queue);
        *ok = false;
        return false;
    }
    for (int i = 0; i < g->npoints; i++)
        via[i] = -2;
    via[from] = -1;
    int head = 0, tail = 0;
    queue[tail++] = from;
    while (head < tail && via[to] == -2) {
        int pt = queue[head++];
        for (size_t k = 0; k < nl; k++) {
            if (g->used[k] || g->l->v[k].kind == ISM_LINE_REGULAR)
                continue;
            for (int s = 0; s < 2; s++) {
                int e = (int)(2 * k) + s;
                if (g->node[e] == pt && via[g->node[e ^ 1]] == -2) {
                    via[g->node[e ^ 1]] = e;
                    queue[tail++] = g->node[e ^ 1];
                }
            }
        }
    }
    bool found = via[to] != -2;
    if (found) {
        /* collect the path backwards from `to`, then append its inner points in order; the
         * path visits each point at most once, so the queue (npoints long, no longer needed)
         * holds it whatever its length (it used to stop at 256 lines) */
        int *path = queue, np = 0;
        for (int pt = to; pt != from; pt = g->node[via[pt]])
            path[np++] = via[pt];
        for (int i = np - 1; i >= 0; i--) {
            g->used[path[i] >> 1] = true;
            if (i > 0)
                *ok = *ok && push_loop_point(out, end_point(g->l, path[i] ^ 1));
        }
    }
    if (via != via_in)
        free(via), free(queue);
    return found;
}

/* A chain from a terminal (or dangling) end, closed through shared lines when possible. */
static bool stitch_chain(graph *g, int e0, ism_loops *out)
{
    size_t start = out->npts;
    bool closed, ok;
    int last = walk_chain(g, e0, out, &closed, &ok);
    if (!ok)
        return false;
    if (!closed)
        closed = close_with_shared(g, g->node[last], g->node[e0], out, &ok);
    return ok && close_loop(out, start, closed);
}

/* Shared lines no chain used: one-edge polygons, one per distinct pair of end points. */
static bool leftover_shared(graph *g, ism_loops *out)
{
    for (size_t k = 0; k < g->l->n; k++) {
        if (g->used[k] || g->l->v[k].kind == ISM_LINE_REGULAR)
            continue;
        g->used[k] = true;
        int a = g->node[2 * k], b = g->node[2 * k + 1];
        for (size_t j = k + 1; j < g->l->n; j++) { /* its copies */
            int c = g->node[2 * j], d = g->node[2 * j + 1];
            if (!g->used[j] && g->l->v[j].kind != ISM_LINE_REGULAR &&
                ((c == a && d == b) || (c == b && d == a)))
                g->used[j] = true;
        }
        size_t start = out->npts;
        if (!push_loop_point(out, &g->l->v[k].a) || !push_loop_point(out, &g->l->v[k].b) ||
            !close_loop(out, start, true))
            return false;
    }
    return true;
}

bool ism_stitch(const ism_flines *l, ism_loops *out)
{
    out->npts = out->nloops = 0;
    size_t ne = 2 * l->n;
    if (ne == 0)
        return true;
    graph g; /* build_graph sets what free_graph reads before anything can fail */
    bool ok = build_graph(&g, l);
    /* chains that start at a terminal point or a dangling end */
    for (size_t e = 0; e < ne && ok && !g.plain; e++)
        if (!is_shared(l, (int)e) && !g.used[e >> 1] &&
            (g.terminal[g.node[e]] || g.partner[e] < 0))
            ok = stitch_chain(&g, (int)e, out);
    /* closed loops of single-polygon lines */
    for (size_t k = 0; k < l->n && ok; k++)
        if (!g.used[k] && l->v[k].kind == ISM_LINE_REGULAR)
            ok = stitch_chain(&g, (int)(2 * k), out);
    if (ok && !g.plain)
        ok = leftover_shared(&g, out);
    free_graph(&g);
    return ok;
}

void ism_loops_free(ism_loops *o)
{
    free(o->pts);
    free(o->loops);
    memset(o, 0, sizeof *o);
}
