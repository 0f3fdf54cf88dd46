/* conform_ears.c — clipping a rim loop's backward steps before its rings are made: where a
 * loop along a double curve steps backwards along it (its feet's arclength decreasing
 * against the way the loop runs), every ring quad and zip triangle built under that step
 * turns over (in the chart s = arclength of the foot, d = distance to the curve, the quad
 * (a_i, a_i+1, b_i+1, b_i) with b = foot + t (a − foot) has the sign of s_i+1 − s_i alone).
 * The polygoniser's mesh makes such steps all round a curve that crosses its lattice at an
 * angle: the tube's rim is a staircase whose risers lean back. A riser's outer end is an ear
 * of the hole — the triangle (prev, v, next) lies in the hole, on the curve's side — and
 * clipping it (one new triangle, v leaves the loop) replaces the step back and the tread
 * after it by one step forwards:
 *
 *     d  113 ───── 114          the cut's bay between two risers 112→113, 114→111, both
 *         ╲ ╲ ear   ╲           leaning back: ears (112, 113, 114) then (112, 114, 111)
 *          112 ──────111        leave the loop 112 → 111, a step forwards
 *   curve ───────────────── s
 *
 * An ear is clipped only when it is oriented like the hole (the chart's turn), its new edge
 * steps forwards and does not cross a fold (its ends' normals agree), and no other loop
 * vertex nearby lies inside it.
 *
 * The other way a riser leans back: one kept triangle sticking into the hole, its tip a rim
 * vertex with no other live triangle (a spike). Its two rim edges step back and forth along
 * the curve; the triangle is cut too (cf_drop_spikes), its third edge joins the rim:
 *
 *     2917 ─ 2916           the kept triangle (3464, 3010, 2916) beside the curve: cut,
 *             │ ╲           the loop runs 2916 → 3464 (forwards) instead of 2916 → 3010
 *       3010 ─── 3464       (back half a cell) → 3464 */
#include "core/singular/conform_internal.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>

/* Loop vertices this many places on either side of an ear are checked to lie outside it (a
 * staircase's neighbours; a vertex farther along the loop is farther along the curve). */
#define EAR_WINDOW 6
/* A loop keeps at least this many vertices when its spikes are dropped (three: a triangle;
 * one more, so the hole left is never a lone sliver). */
#define SPIKE_MIN_LOOP 4
/* A step forwards shorter than this × the loop's mean edge is a riser too: the ring columns
 * under it run a sliver apart, nearly across the curve, and the zip's triangle on the
 * innermost row's riser edge turns over when the curve vertex it is joined to lies behind it
 * (crossing spheres in the lattice box: 17 such edges 0.5 cells from the double circle, the
 * riser's feet 0.014 cells apart). */
#define EAR_MIN_STEP 0.25
/* An ear's height over its new edge is at least this × that edge's length (in the chart): a
 * flatter one is a sliver along a straight stretch of rim (two rim vertices a rounding apart
 * on it), whose normal says nothing about the sheet. */
#define EAR_MIN_HEIGHT 0.1
/* The way a loop runs along an open curve (or beside a stretch of a closed one, without
 * winding round it) is read from its steps this many edges either side of a vertex... */
#define DIR_WINDOW 3
/* ... where their sum is at least this share of their lengths (a rim turning round a pinch
 * point, or zigzagging, is left as it is) and this many mean rim edges long (the window's six
 * edges run about six along a curve; round its end, where the feet stay at the end point,
 * rounding would give any sign). */
#define DIR_AGREE 0.5
#define DIR_TRAVEL 1.0
/* Clipping passes over the loop at most (each clips a riser's ears; a riser clipped lets its
 * neighbour's ear through on the next pass). */
#define EAR_PASSES 4

/* s − t along the curve: wrapped into (−L/2, L/2] on a closed curve of length L (the short
 * way round). */
static double diff(const cf_polyline *pl, double s, double t)
{
    double d = s - t;
    return pl->closed ? d - pl->length * round(d / pl->length) : d;
}

typedef struct chart {
    const cf_polyline *pl; /* the curve of the vertices compared (one run's) */
    const double *u, *d; /* per loop vertex: foot arclength, distance to the curve */
    double sign;         /* +1 when the loop runs with the curve's arclength here, −1 against */
} chart;

/* The step from loop vertex i to j along the loop's way (positive: forwards). */
static double step(const chart *ch, size_t i, size_t j)
{
    return ch->sign * diff(ch->pl, ch->u[j], ch->u[i]);
}

/* Twice the signed area of (i, j, k) in the chart, relative to i; negative when the triangle
 * turns like the hole (the curve lies on its inner side: for a step forwards from i to j and
 * k nearer the curve, (s_j − s_i)(d_k − d_i) − (d_j − d_i)(s_k − s_i) < 0). */
static double chart_turn(const chart *ch, size_t i, size_t j, size_t k)
{
    double sj = step(ch, i, j), sk = step(ch, i, k);
    double dj = ch->d[j] - ch->d[i], dk = ch->d[k] - ch->d[i];
    return sj * dk - dj * sk;
}

/* True when loop vertex q lies inside or on the chart triangle (a, b, e) (turning like the
 * hole). */
static bool inside(const chart *ch, size_t a, size_t b, size_t e, size_t q)
{
    return chart_turn(ch, a, b, q) <= 0 && chart_turn(ch, b, e, q) <= 0 &&
           chart_turn(ch, e, a, q) <= 0;
}

/* The ear at i (prev p, next n over the live vertices) may be clipped: its new edge steps
 * forwards (by less than a riser at times: a short tread after a riser, crossing spheres at
 * depth 8 in the 1e-3 box, 34 edges turned over when the new edge had to step a riser's
 * length). The ends of an open loop are their own neighbours (never clipped). */
static bool ear_ok(const chart *ch, const size_t *prev, const size_t *next, size_t p, size_t i,
                   size_t n)
{
    double sn = step(ch, p, n), dn = ch->d[n] - ch->d[p];
    if (p == n || p == i || n == i || !(sn > 0) ||
        !(chart_turn(ch, p, i, n) < -EAR_MIN_HEIGHT * (sn * sn + dn * dn)))
        return false;
    size_t a = prev[p], b = next[n];
    for (int k = 0; k < EAR_WINDOW; k++, a = prev[a], b = next[b])
        if ((a != i && a != n && a != p && inside(ch, p, i, n, a)) ||
            (b != i && b != p && b != n && inside(ch, p, i, n, b)))
            return false;
    return true;
}

/* True when the ends of an ear's new edge lie on the two sides of a fold: their normals (∇f's
 * direction) point against each other. Beside a pinch point the umbrella's two sheets close
 * in a lens thinner than E (the cross-cap's at x = ±0.0086 round (0, 0.17, 0.97), default
 * bound, 1e-3 box: E 0.0042), and a rim running round the pinch crosses its fold, which the
 * chart's s does not see; an ear there (let through once its neighbours took the chart's
 * lent way) joined a rim vertex at x = 0.020 to one at x = −0.0085, and the rings under the
 * new edge bridged the lens: midpoints 1.94 E off f = 0 the refill could not halve (a half
 * would turn over). A normal of 0 (none) is no evidence either way. */
static bool across_fold(const cf_ctx *c, uint32_t a, uint32_t b)
{
    const float *na = c->m->normal + 3 * (size_t)a, *nb = c->m->normal + 3 * (size_t)b;
    return (double)na[0] * nb[0] + (double)na[1] * nb[1] + (double)na[2] * nb[2] < 0;
}

/* The way the loop runs along the curve at each vertex (sg[i] = ±1), or 0 where it is not
 * clear: round the closed curve it winds (wind != 0), the winding's everywhere; else the
 * sign of the steps over DIR_WINDOW edges each side where they agree (|sum| at least
 * DIR_AGREE of the sum of their lengths) and move at least travel along the curve (a rim
 * round the end of an open curve — a pinch point, a box exit — has its feet at that end),
 * or, when lend_travel > 0, at least lend_travel: then lent[i] = 1 where they move less
 * than travel (a way lent by the chart's own step; lent is left as it is elsewhere). */
static void directions(const cf_polyline *pl, const cf_loop *l, const double *u,
                       const int *cid, int wind, double travel, double lend_travel,
                       double *sg, uint8_t *lent)
{
    size_t n = l->n;
    for (size_t i = 0; i < n; i++) {
        if (wind != 0) {
            sg[i] = wind > 0 ? 1 : -1;
            continue;
        }
        sg[i] = 0;
        if (!l->closed && (i < DIR_WINDOW || i + DIR_WINDOW >= n))
            continue;
        const cf_polyline *c = &pl[cid ? cid[i] : 0];
        double sum = 0, len = 0;
        bool one = true; /* the window along one curve of the group */
        for (size_t k = 0; k < 2 * DIR_WINDOW && one; k++) {
            size_t a = (i + n - DIR_WINDOW + k) % n, b = (a + 1) % n;
            one = !cid || (cid[a] == cid[i] && cid[b] == cid[i]);
            double dd = diff(c, u[b], u[a]);
            sum += dd;
            len += fabs(dd);
        }
        if (one && fabs(sum) >= DIR_AGREE * len &&
            (fabs(sum) >= travel || (lend_travel > 0 && fabs(sum) >= lend_travel))) {
            sg[i] = sum > 0 ? 1 : -1;
            lent[i] = !(fabs(sum) >= travel);
        }
    }
}

/* Every live vertex within EAR_WINDOW + 1 places of i on i's curve (a loop along several
 * curves: an ear and the vertices it is checked against all along one). */
static bool window_on(const int *cid, const size_t *prev, const size_t *next, size_t i)
{
    size_t a = i, b = i;
    for (int k = 0; k <= EAR_WINDOW; k++, a = prev[a], b = next[b])
        if (cid[a] != cid[i] || cid[b] != cid[i])
            return false;
    return true;
}

int cf_clip_ears(cf_ctx *c, const cf_polyline *pl, cf_loop *l, double *u, double *foot,
                 int *cid, int wind, double unit)
{
    size_t n = l->n;
    if (n < 5 || (wind != 0 && !(pl->closed && l->closed)))
        return 0;
    size_t *prev = malloc(n * sizeof *prev), *next = malloc(n * sizeof *next);
    double *d = malloc(n * sizeof *d), *sg = malloc(n * sizeof *sg);
    uint8_t *gone = calloc(n, 1), *lent = calloc(n, 1);
    if (!prev || !next || !d || !sg || !gone || !lent) {
        free(prev);
        free(next);
        free(d);
        free(sg);
        free(gone);
        free(lent);
        return -1;
    }
    for (size_t i = 0; i < n; i++) {
        prev[i] = l->closed || i > 0 ? (i + n - 1) % n : i;
        next[i] = l->closed || i + 1 < n ? (i + 1) % n : i;
        d[i] = ism_dist3(c->m->pos + 3 * (size_t)l->v[i], foot + 3 * i);
    }
    double edge = cf_loop_mean_edge(c, l), riser = EAR_MIN_STEP * edge;
    /* where the mean edge reads no way, the chart's own step may (lent) */
    directions(pl, l, u, cid, wind, DIR_TRAVEL * edge, unit > 0 ? DIR_TRAVEL * unit : 0, sg,
               lent);
    chart ch = {pl, u, d, 1};
    size_t live = n;
    int clipped = 0;
    bool ok = true, any = true;
    for (int pass = 0; ok && any && pass < EAR_PASSES && live > 4; pass++) {
        any = false;
        size_t i = 0;
        while (gone[i])
            i++;
        for (size_t seen = 0; ok && seen < live && live > 4; seen++) {
            size_t p = prev[i], nx = next[i];
            ch.sign = sg[i];
            ch.pl = &pl[cid ? cid[i] : 0];
            /* a step back into i or out of it: clip i when its ear allows (the loop running
             * the same way at its neighbours) */
            double in = step(&ch, p, i), out = step(&ch, i, nx);
            bool back = sg[i] != 0 && sg[p] == sg[i] && sg[nx] == sg[i] &&
                        (!cid || window_on(cid, prev, next, i)) &&
                        (lent[i] ? in < 0 || out < 0 /* a lent way: only steps backwards */
                                 : !(in > riser) || !(out > riser));
            if (back && ear_ok(&ch, prev, next, p, i, nx) &&
                !across_fold(c, l->v[p], l->v[nx])) {
                ok = cf_add_triangle(c, l->v[p], l->v[i], l->v[nx]);
                next[p] = nx;
                prev[nx] = p;
                gone[i] = 1;
                live--;
                clipped++;
                any = true;
                i = p; /* p's ear changed: look at it again */
                continue;
            }
            i = nx;
        }
    }
    if (ok && clipped > 0) { /* compact the loop, its parameters and feet */
        size_t k = 0;
        for (size_t i = 0; i < n; i++) {
            if (gone[i])
                continue;
            l->v[k] = l->v[i];
            u[k] = u[i];
            if (cid)
                cid[k] = cid[i];
            for (int j = 0; j < 3; j++)
                foot[3 * k + j] = foot[3 * i + j];
            k++;
        }
        l->n = k;
    }
    free(prev);
    free(next);
    free(d);
    free(sg);
    free(gone);
    free(lent);
    return ok ? clipped : -1;
}

/* The one live triangle at v when v has exactly one, it holds p and n too, and a kept
 * triangle lies across its third edge pn (which then joins the rim); CF_NONE otherwise. */
static uint32_t lone_triangle(const cf_ctx *c, uint32_t p, uint32_t v, uint32_t n)
{
    cf_inc it;
    uint32_t t, only = CF_NONE;
    size_t count = 0;
    for (cf_inc_begin(c, v, &it); cf_inc_next(c, &it, &t) && count < 2;) {
        only = t;
        count++;
    }
    if (count != 1)
        return CF_NONE;
    const uint32_t *w = c->m->tri + 3 * (size_t)only;
    bool has_p = w[0] == p || w[1] == p || w[2] == p, has_n = w[0] == n || w[1] == n || w[2] == n;
    return has_p && has_n && cf_live_on_edge(c, p, n, NULL, 0) == 2 ? only : CF_NONE;
}

bool cf_drop_spikes(cf_ctx *c, cf_loops *ls, uint32_t **rm, size_t *nrm)
{
    uint32_t *add = NULL;
    size_t na = 0, cap = 0;
    bool ok = true;
    for (size_t k = 0; ok && k < ls->n; k++) {
        cf_loop *l = &ls->l[k];
        if (!l->closed)
            continue;
        size_t m = 0;
        for (size_t i = 0; i < l->n; i++) {
            uint32_t p = m > 0 ? l->v[m - 1] : l->v[l->n - 1], v = l->v[i];
            uint32_t n = l->v[(i + 1) % l->n];
            uint32_t t = ok && l->n - (i - m) > SPIKE_MIN_LOOP ? lone_triangle(c, p, v, n) : CF_NONE;
            if (t != CF_NONE && na == cap) {
                uint32_t *a = realloc(add, (cap = cap ? 2 * cap : 16) * sizeof *a);
                ok = a != NULL;
                add = ok ? a : add;
            }
            if (t == CF_NONE || !ok) {
                l->v[m++] = v;
                continue;
            }
            add[na++] = t;
            c->dead[t] = 1;
        }
        l->n = m;
    }
    /* merged into the sorted list from its end (the few added sorted first) */
    uint32_t *r = ok && na ? realloc(*rm, (*nrm + na) * sizeof *r) : *rm;
    if (na && !r) {
        ok = false;
        r = *rm;
    }
    *rm = r;
    if (ok && na) {
        cf_sort_u32(add, na);
        size_t i = *nrm, j = na, o = *nrm + na;
        while (j > 0)
            r[--o] = i > 0 && r[i - 1] > add[j - 1] ? r[--i] : add[--j];
        *nrm += na;
    } else if (!ok) { /* out of memory: the triangles marked are listed all the same */
        for (size_t j = 0; j < na; j++)
            c->dead[add[j]] = 0;
    }
    free(add);
    return ok;
}
