/* conform_kept.c — double curves the polygoniser's mesh already follows: where flat sheets lie
 * on lattice planes (x y z = 0 in a box symmetric about them), their crossing lines are
 * lattice lines, the polygoniser puts vertices on them at zero corners, and the four cells
 * round each lattice edge give that edge two triangles from each sheet. The tube surgery
 * (conform_tube.c) would cut those triangles and zip them back with rings of its own: the
 * same chain of edges, at the cost of most of the mesh beside the curve (x y z = 0: 9,000 of
 * 12,672 triangles cut and 10,240 made), and with worse triangles. A group of curves whose
 * every curve is found to be such a chain is kept as it is:
 *
 *        sheet B                  each chain edge v-w: exactly four live triangles, their
 *           │                     third vertices pairwise more than 10° apart round the edge
 *    ───────●─────── sheet A      (two sheets, two sides each); every other edge at a chain
 *           │                     vertex one or two triangles (no other non-manifold edge);
 *        v ─●─ w  (the curve)     chain vertices and edge midpoints within the locus's own
 *                                 accuracy of the curve's polyline, the chain running from
 *                                 its first point to its last; every triangle with a corner
 *                                 within the surgery's first radius on f = 0 exactly (f's
 *                                 interval over its box is 0: f's own structure says the
 *                                 sheets there are flat and where the mesh puts them).
 *
 * Anything else (a curve through cells, curved sheets — which the polygoniser leaves coarse
 * near the locus under a bound, for the surgery to mesh again —, an end at a pinch point, a
 * closed curve, a shallow crossing) goes to the surgery as before. */
#include "core/singular/conform_internal.h"
#include "core/util/vec3.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Chain vertices and edge midpoints lie within this fraction of the box diagonal of the
 * curve's polyline: the accuracy the locus gives its traced points (locus.h, 1e-9 ×
 * diagonal) and the surgery its curve vertices (the traced points themselves). */
#define KEPT_TOL_REL 1e-9
/* The four half-sheets at a chain edge are pairwise at least this far apart round it (cos of
 * 10°): two sheets crossing, not a fold or a sheet counted twice; sheets crossing more
 * shallowly than that need the surgery's widened tube (conform_angle.c) anyway. */
#define KEPT_MAX_COS 0.984807753012208
/* f's interval over a kept triangle's box holds no value farther from 0 than the smallest
 * normal double: 0 rounded outwards (the evaluator widens an exact 0 by a denormal). */
#define KEPT_ZERO DBL_MIN
/* A chain vertex with more neighbours than this is not read (none of the polygoniser's has:
 * a lattice vertex has at most 26 neighbours per sheet through it, two sheets here). */
#define KEPT_MAX_NEIGH 64

typedef struct nb {
    uint32_t v;
    int mult; /* live triangles on the edge to v */
} nb;

/* The neighbours of v over its live triangles, each with its edge's triangle count; -1 when
 * there are more than KEPT_MAX_NEIGH. */
static int neighbours(const cf_ctx *c, uint32_t v, nb *out)
{
    int n = 0;
    cf_inc it;
    uint32_t t;
    for (cf_inc_begin(c, v, &it); cf_inc_next(c, &it, &t);) {
        const uint32_t *tv = c->m->tri + 3 * (size_t)t;
        for (int k = 0; k < 3; k++) {
            if (tv[k] == v)
                continue;
            int i = 0;
            while (i < n && out[i].v != tv[k])
                i++;
            if (i == n) {
                if (n == KEPT_MAX_NEIGH)
                    return -1;
                out[n++] = (nb){tv[k], 0};
            }
            out[i].mult++;
        }
    }
    return n;
}

/* The four triangles on edge (a, b) lie on four different half-sheets round it. */
static bool four_sheets(const cf_ctx *c, uint32_t a, uint32_t b)
{
    uint32_t t4[4];
    if (cf_live_on_edge(c, a, b, t4, 4) != 4)
        return false;
    const double *pa = c->m->pos + 3 * (size_t)a, *pb = c->m->pos + 3 * (size_t)b;
    double e[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]}, ee = ism_dot3(e, e), d[4][3];
    if (!(ee > 0))
        return false;
    for (int i = 0; i < 4; i++) {
        const uint32_t *tv = c->m->tri + 3 * (size_t)t4[i];
        uint32_t x = tv[0] != a && tv[0] != b ? tv[0] : tv[1] != a && tv[1] != b ? tv[1] : tv[2];
        double w[3];
        for (int k = 0; k < 3; k++)
            w[k] = c->m->pos[3 * (size_t)x + k] - pa[k];
        double along = ism_dot3(w, e) / ee;
        for (int k = 0; k < 3; k++)
            d[i][k] = w[k] - along * e[k];
        double len = sqrt(ism_dot3(d[i], d[i]));
        if (!(len > 0))
            return false;
        for (int k = 0; k < 3; k++)
            d[i][k] /= len;
    }
    for (int i = 0; i < 4; i++)
        for (int j = i + 1; j < 4; j++)
            if (!(ism_dot3(d[i], d[j]) <= KEPT_MAX_COS))
                return false;
    return true;
}

/* Live triangles at v: at least one. */
static bool live(const cf_ctx *c, uint32_t v)
{
    cf_inc it;
    uint32_t t;
    cf_inc_begin(c, v, &it);
    return cf_inc_next(c, &it, &t);
}

/* The chain of curve pl from vertex v (at its first point) to its last point: its vertices
 * appended to chain (room for cap), *end the last one. False where the mesh does not hold
 * the curve so. */
static bool walk(cf_ctx *c, const cf_polyline *pl, uint32_t v, double tol, uint32_t *chain,
                 size_t *nchain, size_t cap, uint32_t *end)
{
    const double *last = pl->p + 3 * (pl->n - 1);
    uint32_t prev = CF_NONE;
    double s = 0;
    nb list[KEPT_MAX_NEIGH];
    while (*nchain < cap && !cf_poll(c, 1)) {
        chain[(*nchain)++] = v;
        int n = neighbours(c, v, list);
        if (n < 0)
            return false;
        int four = 0;
        uint32_t next = CF_NONE;
        double s_next = 0;
        for (int i = 0; i < n; i++) {
            if (list[i].mult > 2 && list[i].mult != 4)
                return false; /* another non-manifold edge at the chain */
            if (list[i].mult != 4)
                continue;
            four++;
            if (list[i].v == prev)
                continue;
            double sw;
            const double *pw = c->m->pos + 3 * (size_t)list[i].v;
            if (!isfinite(cf_polyline_nearest(pl, pw, tol, &sw, NULL)) || !(sw > s))
                continue; /* another curve's chain at a shared end */
            if (next != CF_NONE)
                return false; /* two ways on */
            next = list[i].v;
            s_next = sw;
        }
        const double *pv = c->m->pos + 3 * (size_t)v;
        if (ism_sqdist3(pv, last) <= tol * tol) {
            *end = v;
            return fabs(s - pl->length) <= tol;
        }
        if (next == CF_NONE || (prev != CF_NONE && four != 2))
            return false;
        const double *pn = c->m->pos + 3 * (size_t)next;
        double mid[3] = {(pv[0] + pn[0]) / 2, (pv[1] + pn[1]) / 2, (pv[2] + pn[2]) / 2};
        if (!isfinite(cf_polyline_nearest(pl, mid, tol, NULL, NULL)) || !four_sheets(c, v, next))
            return false;
        prev = v;
        v = next;
        s = s_next;
    }
    return false;
}

/* start[k]: the one vertex with a live triangle within tol of the first point of pl[k]
 * (CF_NONE when none or several), for the n polylines in one pass over the vertices: those
 * outside the first points' box (grown by tol) are passed over at once (a group's curves
 * mostly start at one junction). */
static void start_vertices(const cf_ctx *c, const cf_polyline *pl, size_t n, double tol,
                           uint32_t *start)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t k = 0; k < n; k++) {
        start[k] = CF_NONE;
        for (int j = 0; j < 3; j++) {
            lo[j] = cf_min2(lo[j], pl[k].p[j] - tol);
            hi[j] = cf_max2(hi[j], pl[k].p[j] + tol);
        }
    }
    bool *several = calloc(n, sizeof *several);
    if (!several)
        return; /* none found: not kept */
    for (size_t v = 0; v < c->m->nverts; v++) {
        const double *q = c->m->pos + 3 * v;
        if (!(q[0] >= lo[0] && q[0] <= hi[0] && q[1] >= lo[1] && q[1] <= hi[1] &&
              q[2] >= lo[2] && q[2] <= hi[2]))
            continue;
        for (size_t k = 0; k < n; k++)
            if (ism_sqdist3(q, pl[k].p) <= tol * tol && live(c, (uint32_t)v)) {
                several[k] |= start[k] != CF_NONE;
                start[k] = (uint32_t)v;
            }
    }
    for (size_t k = 0; k < n; k++)
        if (several[k])
            start[k] = CF_NONE;
    free(several);
}

/* The first of the n polylines, curve `first` asked first, whose points' box lies within r
 * of p (n when none): a vertex beside a chain is mostly near the chain's own curve. The box
 * holds the curve (a straight one along an axis is its own box), so the vertices within r
 * of a curve are all found, and a few more (a query of the box costs a tenth of one of the
 * polyline's segments, x y z = 0: 5.4M instructions for 11.8k queries). */
static size_t near_curve(const cf_polyline *pl, size_t n, size_t first, const double p[3],
                         double r)
{
    if (cf_polyline_box_distance(&pl[first], p) <= r)
        return first;
    for (size_t k = 0; k < n; k++)
        if (k != first && cf_polyline_box_distance(&pl[k], p) <= r)
            return k;
    return n;
}

/* f vanishes on triangle t: the interval of f over its bounding box holds nothing but a
 * rounded 0 (KEPT_ZERO), as on a plane of the lattice where one of f's factors is [0, 0]. */
static bool on_zero_set(cf_ctx *c, uint32_t t)
{
    const uint32_t *tv = c->m->tri + 3 * (size_t)t;
    ism_interval box[3];
    for (int k = 0; k < 3; k++) {
        double a = c->m->pos[3 * (size_t)tv[0] + k], b = c->m->pos[3 * (size_t)tv[1] + k],
               d = c->m->pos[3 * (size_t)tv[2] + k];
        box[k] = (ism_interval){cf_min2(a, cf_min2(b, d)), cf_max2(a, cf_max2(b, d))};
    }
    ism_interval f = ism_eval_interval(c->f, c->ws, box[0], box[1], box[2]);
    return fabs(f.lo) <= KEPT_ZERO && fabs(f.hi) <= KEPT_ZERO;
}

/* Every live triangle with a corner within r of the n curves (found from the chains'
 * vertices over the incidence, near_curve; chain[i] on curve of[i]) lies on f = 0
 * (on_zero_set). */
static bool region_exact(cf_ctx *c, const cf_polyline *pl, size_t n, const uint32_t *chain,
                         const uint32_t *of, size_t nchain, double r)
{
    const ism_mesh *m = c->m;
    uint8_t *seen_t = calloc(m->ntris + 1, 1), *seen_v = calloc(m->nverts + 1, 1);
    uint32_t *queue = malloc(2 * (m->nverts + 1) * sizeof *queue); /* vertex, its curve */
    bool ok = seen_t && seen_v && queue;
    size_t head = 0, tail = 0;
    for (size_t i = 0; ok && i < nchain; i++)
        if (!seen_v[chain[i]]) {
            seen_v[chain[i]] = 1;
            queue[2 * tail] = chain[i];
            queue[2 * tail++ + 1] = of[i];
        }
    while (ok && head < tail) {
        cf_inc it;
        uint32_t t, curve = queue[2 * head + 1];
        for (cf_inc_begin(c, queue[2 * head++], &it); ok && cf_inc_next(c, &it, &t);) {
            if (seen_t[t])
                continue;
            seen_t[t] = 1;
            ok = !cf_poll(c, 1) && on_zero_set(c, t);
            for (int k = 0; ok && k < 3; k++) {
                uint32_t w = m->tri[3 * (size_t)t + k];
                if (seen_v[w])
                    continue;
                seen_v[w] = 1;
                size_t near = near_curve(pl, n, curve, m->pos + 3 * (size_t)w, r);
                if (near < n) {
                    queue[2 * tail] = w;
                    queue[2 * tail++ + 1] = (uint32_t)near;
                }
            }
        }
    }
    free(seen_t);
    free(seen_v);
    free(queue);
    return ok;
}

/* Every end vertex has as many four-triangle edges as chains end there: the ends sorted
 * (a copy), each vertex's neighbours read once for its run of equal ends. */
static bool ends_closed(const cf_ctx *c, const uint32_t *ends, size_t nends)
{
    uint32_t *e = malloc(nends * sizeof *e);
    if (!e)
        return false; /* out of memory: not kept */
    memcpy(e, ends, nends * sizeof *e);
    cf_sort_u32(e, nends);
    nb list[KEPT_MAX_NEIGH];
    bool ok = true;
    for (size_t i = 0, at; ok && i < nends; i += at) {
        for (at = 1; i + at < nends && e[i + at] == e[i]; at++)
            ;
        int n = neighbours(c, e[i], list), four = 0;
        for (int k = 0; k < n; k++)
            four += list[k].mult == 4;
        ok = n >= 0 && (size_t)four == at;
    }
    free(e);
    return ok;
}

bool cf_curves_kept(cf_run *r, const cf_polyline *pl, const ism_sing_curve *const *cu, size_t n)
{
    cf_ctx *c = &r->c;
    double tol = KEPT_TOL_REL * ism_box_diagonal(r->o->box);
    for (size_t k = 0; k < n; k++)
        if (cu[k]->closed || pl[k].pinch[0] || pl[k].pinch[1]) /* pl closed: cu too */
            return false;
    /* room for every vertex once and the ends again (chains share only their ends) */
    size_t cap = c->m->nverts + 2 * n + 1, nchain = 0;
    uint32_t *chain = malloc(cap * sizeof *chain), *of = malloc(cap * sizeof *of);
    uint32_t *ends = malloc(2 * n * sizeof *ends), *start = malloc(n * sizeof *start);
    bool kept = chain && of && ends && start;
    if (kept)
        start_vertices(c, pl, n, tol, start);
    for (size_t k = 0; kept && k < n; k++) {
        size_t from = nchain;
        kept = start[k] != CF_NONE &&
               walk(c, &pl[k], start[k], tol, chain, &nchain, cap, &ends[2 * k + 1]);
        ends[2 * k] = start[k];
        for (size_t i = from; i < nchain; i++)
            of[i] = (uint32_t)k;
        for (int e = 0; kept && e < 2; e++) {
            int p = cu[k]->end_point[e];
            uint32_t at = ends[2 * k + e];
            kept = p < 0 || (size_t)p >= r->l->npoints || r->point_vertex[p] == CF_NONE ||
                   r->point_vertex[p] == at;
        }
    }
    /* the tube the surgery would cut first (CF_RHO_CELLS cells) lies on f = 0: the
     * polygoniser left nodes whole there under a bound for the surgery to mesh again
     * (octree_build.c conformed()), and triangles on the zero set need nothing of it */
    kept = kept && !c->stopped && ends_closed(c, ends, 2 * n) &&
           region_exact(c, pl, n, chain, of, nchain, CF_RHO_CELLS * c->cell);
    /* kept: the chains' vertices are the curves' (their normals from their triangles, as
     * the surgery's curve vertices, cf_compact), the ends the points' shared vertices */
    for (size_t i = 0; kept && i < nchain; i++)
        c->singular[chain[i]] |= CF_VERTEX_SINGULAR;
    for (size_t k = 0; kept && k < n; k++)
        for (int e = 0; e < 2; e++) {
            int p = cu[k]->end_point[e];
            if (p >= 0 && (size_t)p < r->l->npoints)
                r->point_vertex[p] = ends[2 * k + e];
        }
    free(chain);
    free(of);
    free(ends);
    free(start);
    return kept;
}
