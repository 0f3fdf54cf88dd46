/* conform_hole.c — cutting a hole into the mesh around a piece of the locus and finding its
 * rim: the triangles a predicate selects are marked dead, the edges left with exactly one
 * live triangle (that lost one) are the rim, chained into loops — one per cone of a node,
 * one per side of each sheet along a double curve — and oriented against their live
 * triangle so the refill continues each sheet's orientation.
 *
 *        live  ╲  ╱  live         rim edge a→b of a live triangle: the refill uses b→a
 *      ─────────●────────
 *        dead  (hole)  dead
 */
#include "core/singular/conform_internal.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct rim_edge {
    uint32_t from, to;   /* the direction new triangles traverse */
    uint32_t lo, hi;     /* sorted ends (for removing duplicates) */
    uint32_t live;       /* the live triangle on it */
} rim_edge;

void cf_loops_free(cf_loops *ls)
{
    for (size_t i = 0; i < ls->n; i++)
        free(ls->l[i].v);
    free(ls->l);
    memset(ls, 0, sizeof *ls);
}

double cf_point_triangle_d2(const double q[3], const double a[3], const double b[3],
                            const double c[3])
{
    /* closest point by Voronoi regions of the triangle (vertices, edges, face) */
    double ab[3], ac[3], ap[3], r[3];
    for (int k = 0; k < 3; k++) {
        ab[k] = b[k] - a[k];
        ac[k] = c[k] - a[k];
        ap[k] = q[k] - a[k];
    }
    double d1 = ism_dot3(ab, ap), d2 = ism_dot3(ac, ap);
    double bp[3], cp[3];
    for (int k = 0; k < 3; k++) {
        bp[k] = q[k] - b[k];
        cp[k] = q[k] - c[k];
    }
    double d3 = ism_dot3(ab, bp), d4 = ism_dot3(ac, bp);
    double d5 = ism_dot3(ab, cp), d6 = ism_dot3(ac, cp);
    double u = 0, v = 0; /* r = a + u ab + v ac */
    double va = d3 * d6 - d5 * d4, vb = d5 * d2 - d1 * d6, vc = d1 * d4 - d3 * d2;
    if (d1 <= 0 && d2 <= 0) {
        u = v = 0;
    } else if (d3 >= 0 && d4 <= d3) {
        u = 1;
    } else if (d6 >= 0 && d5 <= d6) {
        v = 1;
    } else if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        u = d1 / (d1 - d3);
    } else if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        v = d2 / (d2 - d6);
    } else if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
        double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        u = 1 - w;
        v = w;
    } else {
        double den = va + vb + vc;
        if (!(fabs(den) > 0))
            return fmin(ism_dot3(ap, ap), fmin(ism_dot3(bp, bp), ism_dot3(cp, cp)));
        u = vb / den;
        v = vc / den;
    }
    for (int k = 0; k < 3; k++)
        r[k] = a[k] + u * ab[k] + v * ac[k] - q[k];
    return ism_dot3(r, r);
}

static int cmp_rim(const void *pa, const void *pb)
{
    const rim_edge *a = pa, *b = pb;
    if (a->lo != b->lo)
        return a->lo < b->lo ? -1 : 1;
    return a->hi < b->hi ? -1 : a->hi > b->hi;
}

/* Whether vertex v keeps a live triangle (lives[v]: 0 not asked yet, 1 none, 2 some). */
static bool keeps_live(const cf_ctx *c, uint8_t *lives, uint32_t v)
{
    if (!lives[v]) {
        cf_inc it;
        uint32_t t;
        cf_inc_begin(c, v, &it);
        lives[v] = cf_inc_next(c, &it, &t) ? 2 : 1;
    }
    return lives[v] == 2;
}

/* The rim edges of the dead triangles, each once, directed for the refill. Most edges of a
 * cut lie inside it, at a vertex that kept no live triangle: each vertex is asked that once
 * (its first live triangle), and only the edges between two vertices that kept one are
 * counted (crossing-spheres: 90k edge counts, 14.7M instructions, callgrind). */
static bool rim_edges(cf_ctx *c, const uint32_t *rm, size_t nrm, rim_edge **out,
                      size_t *nout)
{
    rim_edge *e = malloc((3 * nrm + 1) * sizeof *e);
    uint8_t *lives = calloc(c->m->nverts + 1, 1);
    if (!e || !lives) {
        free(e);
        free(lives);
        return false;
    }
    size_t n = 0;
    for (size_t i = 0; i < nrm && !cf_poll(c, 1); i++) {
        const uint32_t *v = c->m->tri + 3 * (size_t)rm[i];
        for (int k = 0; k < 3; k++) {
            uint32_t a = v[k], b = v[(k + 1) % 3], t = 0;
            if (!keeps_live(c, lives, a) || !keeps_live(c, lives, b) ||
                cf_live_on_edge(c, a, b, &t, 1) != 1)
                continue;
            const uint32_t *w = c->m->tri + 3 * (size_t)t;
            bool ab = (w[0] == a && w[1] == b) || (w[1] == a && w[2] == b) ||
                      (w[2] == a && w[0] == b);
            e[n].from = ab ? b : a;
            e[n].to = ab ? a : b;
            e[n].lo = a < b ? a : b;
            e[n].hi = a < b ? b : a;
            e[n].live = t;
            n++;
        }
    }
    free(lives);
    qsort(e, n, sizeof *e, cmp_rim);
    size_t u = 0;
    for (size_t i = 0; i < n; i++)
        if (u == 0 || cmp_rim(&e[u - 1], &e[i]) != 0)
            e[u++] = e[i];
    *out = e;
    *nout = u;
    return true;
}

/* Rim edges by vertex: for each end vertex, the edges at it (CSR over a sorted key list). */
typedef struct rim_adj {
    uint32_t *vert;   /* sorted distinct vertices */
    size_t nvert;
    uint32_t *start;  /* nvert + 1 */
    uint32_t *edge;
} rim_adj;

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

static bool rim_adj_build(const rim_edge *e, size_t n, rim_adj *ad)
{
    uint64_t *key = malloc((2 * n + 1) * sizeof *key);
    ad->vert = malloc((2 * n + 1) * sizeof *ad->vert);
    ad->start = malloc((2 * n + 2) * sizeof *ad->start);
    ad->edge = malloc((2 * n + 1) * sizeof *ad->edge);
    if (!key || !ad->vert || !ad->start || !ad->edge) {
        free(key);
        return false;
    }
    for (size_t i = 0; i < n; i++) {
        key[2 * i] = (uint64_t)e[i].from << 32 | i;
        key[2 * i + 1] = (uint64_t)e[i].to << 32 | i;
    }
    qsort(key, 2 * n, sizeof *key, cmp_u64);
    ad->nvert = 0;
    for (size_t i = 0; i < 2 * n; i++) {
        uint32_t v = (uint32_t)(key[i] >> 32);
        if (ad->nvert == 0 || ad->vert[ad->nvert - 1] != v) {
            ad->vert[ad->nvert] = v;
            ad->start[ad->nvert++] = (uint32_t)i;
        }
        ad->edge[i] = (uint32_t)key[i];
    }
    ad->start[ad->nvert] = (uint32_t)(2 * n);
    free(key);
    return true;
}

static void rim_adj_free(rim_adj *ad)
{
    free(ad->vert);
    free(ad->start);
    free(ad->edge);
}

static size_t rim_slot(const rim_adj *ad, uint32_t v)
{
    size_t lo = 0, hi = ad->nvert;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (ad->vert[mid] < v)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* The next unused rim edge at vertex v: one leaving v in the refill direction if any. */
static long next_edge(const rim_edge *e, const rim_adj *ad, const uint8_t *used, uint32_t v)
{
    size_t s = rim_slot(ad, v);
    long any = -1;
    for (uint32_t i = ad->start[s]; i < ad->start[s + 1]; i++) {
        uint32_t k = ad->edge[i];
        if (used[k])
            continue;
        if (e[k].from == v)
            return k;
        if (any < 0)
            any = k;
    }
    return any;
}

static bool push_loop(cf_loops *ls, uint32_t *v, size_t n, bool closed)
{
    if (ls->n == ls->cap) {
        size_t cap = ls->cap ? 2 * ls->cap : 8;
        cf_loop *p = realloc(ls->l, cap * sizeof *p);
        if (!p)
            return false;
        ls->l = p;
        ls->cap = cap;
    }
    ls->l[ls->n++] = (cf_loop){v, n, closed};
    return true;
}

/* Walks unused rim edges from v0 until stuck or back at v0; orients the chain by the
 * majority of its edges' refill directions. */
static bool walk(const rim_edge *e, size_t ne, const rim_adj *ad, uint8_t *used, uint32_t v0,
                 cf_loops *ls)
{
    uint32_t *seq = malloc((ne + 2) * sizeof *seq);
    if (!seq)
        return false;
    size_t n = 0;
    long vote = 0;
    uint32_t cur = v0;
    seq[n++] = cur;
    bool closed = false;
    for (long k; (k = next_edge(e, ad, used, cur)) >= 0;) {
        used[k] = 1;
        vote += e[k].from == cur ? 1 : -1;
        cur = e[k].from == cur ? e[k].to : e[k].from;
        if (cur == v0) {
            closed = true;
            break;
        }
        seq[n++] = cur;
    }
    if (vote < 0)
        for (size_t i = 0; i < n / 2; i++) {
            uint32_t t = seq[i];
            seq[i] = seq[n - 1 - i];
            seq[n - 1 - i] = t;
        }
    if (n < 2 || (closed && n < 3)) {
        free(seq); /* a lone edge or a digon: nothing to refill */
        return true;
    }
    if (!push_loop(ls, seq, n, closed)) {
        free(seq);
        return false;
    }
    return true;
}

static bool chain_rim(const rim_edge *e, size_t ne, cf_loops *ls)
{
    rim_adj ad = {0};
    uint8_t *used = calloc(ne + 1, 1);
    bool ok = used && rim_adj_build(e, ne, &ad);
    /* open chains first, from the vertices with an odd number of rim edges (the box) */
    for (size_t s = 0; ok && s < ad.nvert; s++)
        if ((ad.start[s + 1] - ad.start[s]) % 2 == 1)
            while (ok && next_edge(e, &ad, used, ad.vert[s]) >= 0)
                ok = walk(e, ne, &ad, used, ad.vert[s], ls);
    for (size_t k = 0; ok && k < ne; k++)
        if (!used[k])
            ok = walk(e, ne, &ad, used, e[k].from, ls);
    rim_adj_free(&ad);
    free(used);
    return ok;
}

/* The live triangles the cutter selects, in increasing order: its candidates, sorted, then
 * tested one by one. */
static bool select_triangles(cf_ctx *c, const cf_cutter *cut, uint32_t **out, size_t *nout)
{
    cf_tris cand = {0};
    cf_tgrid_begin(&c->grid);
    if (!cut->gather(c, cut->arg, &cand)) {
        free(cand.t);
        return false;
    }
    cf_sort_u32(cand.t, cand.n);
    size_t n = 0;
    for (size_t i = 0; i < cand.n && !cf_poll(c, 1); i++)
        if (!c->dead[cand.t[i]] && cut->near(c, cand.t[i], cut->arg))
            cand.t[n++] = cand.t[i];
    *out = cand.t;
    *nout = n;
    return true;
}

/* Kept pieces of at most this many triangles that the cut encloses (every edge of the
 * piece's boundary shared with a removed triangle) are removed too, else each is a rim loop
 * of its own. The cut's boundary wiggles by about a cell, which leaves single triangles and
 * pairs behind; a larger piece is a part of a sheet that the cut passes by, and its rim
 * joins the cut's. */
#define ISLAND_MAX_TRIS 8

typedef struct island {
    uint32_t t[ISLAND_MAX_TRIS];
    size_t n;
} island;

/* Adds live triangle u to the island; false when it outgrows ISLAND_MAX_TRIS. */
static bool island_add(island *is, uint32_t u)
{
    for (size_t i = 0; i < is->n; i++)
        if (is->t[i] == u)
            return true;
    if (is->n == ISLAND_MAX_TRIS)
        return false;
    is->t[is->n++] = u;
    return true;
}

/* Floods from live triangle t through live triangles sharing an edge (dead ones are the
 * cut): true with the piece in is when it closes within ISLAND_MAX_TRIS triangles. */
static bool enclosed_island(const cf_ctx *c, uint32_t t, island *is)
{
    is->n = 0;
    island_add(is, t);
    for (size_t i = 0; i < is->n; i++) {
        const uint32_t *v = c->m->tri + 3 * (size_t)is->t[i];
        for (int k = 0; k < 3; k++) {
            uint32_t a = v[k], b = v[(k + 1) % 3], u;
            cf_inc it;
            for (cf_inc_begin(c, a, &it); cf_inc_next(c, &it, &u);) {
                const uint32_t *w = c->m->tri + 3 * (size_t)u;
                if ((w[0] == b || w[1] == b || w[2] == b) && !island_add(is, u))
                    return false;
            }
        }
    }
    return true;
}

/* Removes the kept pieces the cut encloses (ISLAND_MAX_TRIS), found from the live triangles
 * on its rim e[0..ne), appending them to *rm (*n); *grew when there were any.
 *
 *     ╲ cut ╱╲ cut ╱      the triangle in the middle kept no corner and no sample within
 *      ╲   ╱kept╲ ╱       the radius, but each of its neighbours did: kept, it is a rim
 *       ╲ ╱______╲        loop of three of its own, zipped to the curve across the hole
 *                         (a pinch point's tube at depth 5, 0.37 cell off the lattice)
 */
static bool absorb_islands(cf_ctx *c, const rim_edge *e, size_t ne, uint32_t **rm, size_t *n,
                           bool *grew)
{
    *grew = false;
    for (size_t k = 0; k < ne; k++) {
        island is;
        if (c->dead[e[k].live] || !enclosed_island(c, e[k].live, &is))
            continue;
        uint32_t *r = realloc(*rm, (*n + is.n) * sizeof *r);
        if (!r)
            return false;
        *rm = r;
        for (size_t i = 0; i < is.n; i++) {
            c->dead[is.t[i]] = 1;
            r[(*n)++] = is.t[i];
        }
        *grew = true;
    }
    if (*grew)
        cf_sort_u32(*rm, *n);
    return true;
}

/* Marks dead the live triangles the cutter selects now and merges them into the sorted list
 * *rm of n removed before (a wider cut removes all a narrower one did: only the triangles
 * still live are tested again). False when out of memory (nothing more marked then). */
static bool cut_more(cf_ctx *c, const cf_cutter *cut, uint32_t **rm, size_t *n)
{
    uint32_t *add = NULL;
    size_t na = 0;
    if (!select_triangles(c, cut, &add, &na))
        return false;
    uint32_t *m = na ? malloc((*n + na) * sizeof *m) : NULL;
    if (na && !m) {
        free(add);
        return false;
    }
    size_t i = 0, j = 0, k = 0;
    while (na && (i < *n || j < na))
        m[k++] = j == na || (i < *n && (*rm)[i] < add[j]) ? (*rm)[i++] : add[j++];
    for (j = 0; j < na; j++)
        c->dead[add[j]] = 1;
    free(add);
    if (na) {
        free(*rm);
        *rm = m;
        *n += na;
    }
    return true;
}

/* The hole's rim around the removed triangles *rm (n), the kept pieces of a few triangles
 * the cut encloses removed too (added to *rm), chained into loops (out emptied first).
 * False when out of memory (out then empty). */
static bool rim_loops(cf_ctx *c, uint32_t **rm, size_t *n, cf_loops *out)
{
    memset(out, 0, sizeof *out);
    rim_edge *e = NULL;
    size_t ne = 0;
    bool grew = false;
    bool ok = rim_edges(c, *rm, *n, &e, &ne) && absorb_islands(c, e, ne, rm, n, &grew);
    if (ok && grew) {
        free(e);
        e = NULL;
        ok = rim_edges(c, *rm, *n, &e, &ne);
    }
    ok = ok && chain_rim(e, ne, out);
    free(e);
    if (!ok)
        cf_loops_free(out);
    return ok;
}

void cf_undo(cf_ctx *c, const uint32_t *removed, size_t nremoved, size_t ntris, size_t nverts)
{
    for (size_t i = 0; i < nremoved; i++)
        c->dead[removed[i]] = 0;
    cf_truncate(c, ntris, nverts);
}

/* Samples of f per side along a rim vertex's normal when looking for another sheet. */
#define CLEAR_SAMPLES 8
/* batch_clear takes whole vertices: a full batch holds a whole number of them. */
_Static_assert(ISM_EVAL_BATCH % (2 * CLEAR_SAMPLES) == 0, "a batch holds whole vertices");
/* True when the samples v[0 .. CLEAR_SAMPLES) along one side change sign beyond the first. */
static bool sheet_along(const double *v)
{
    double prev = 0;
    for (int k = 1; k <= CLEAR_SAMPLES; k++) {
        double w = v[k - 1];
        if (k > 1 && ((w > 0 && prev < 0) || (w < 0 && prev > 0)))
            return true;
        if (w != 0)
            prev = w;
    }
    return false;
}

/* The points p + t n for t = len k / CLEAR_SAMPLES, k = 1 .. CLEAR_SAMPLES, from slot at. */
static void samples_along(const double p[3], const double n[3], double len, double *x,
                          double *y, double *z, size_t at)
{
    for (int k = 1; k <= CLEAR_SAMPLES; k++) {
        double t = len * k / CLEAR_SAMPLES;
        x[at + k - 1] = p[0] + t * n[0];
        y[at + k - 1] = p[1] + t * n[1];
        z[at + k - 1] = p[2] + t * n[2];
    }
}

/* Evaluates the n waiting samples (whole runs of CLEAR_SAMPLES) in one pass and says whether no
 * run meets another sheet. The rim vertices' samples are evaluated a batch at a time
 * (ism_eval_points: one pass over the tape for ISM_EVAL_BATCH / (2 CLEAR_SAMPLES) vertices, each
 * value ism_eval_point's to the bit; one at a time, the samples cost crossing-spheres'
 * conformance 11.3M instructions, callgrind). A vertex found unclear ends the check after its
 * batch, not at once. */
static bool batch_clear(cf_ctx *c, const double *x, const double *y, const double *z, double *v,
                        size_t n)
{
    ism_eval_points(c->f, c->ws, x, y, z, v, n);
    for (size_t k = 0; k < n; k += CLEAR_SAMPLES)
        if (sheet_along(v + k))
            return false;
    return true;
}

bool cf_rim_clear(cf_ctx *c, const cf_loops *ls, double clearance)
{
    double x[ISM_EVAL_BATCH], y[ISM_EVAL_BATCH], z[ISM_EVAL_BATCH], v[ISM_EVAL_BATCH];
    size_t n = 0; /* points waiting */
    for (size_t i = 0; i < ls->n; i++)
        for (size_t j = 0; j < ls->l[i].n; j++) {
            if (cf_poll(c, 1))
                return false; /* the caller sees c->stopped */
            const double *p = c->m->pos + 3 * (size_t)ls->l[i].v[j];
            double g[3];
            ism_eval_gradient(c->f, c->ws, p[0], p[1], p[2], g);
            double gl = sqrt(ism_dot3(g, g));
            if (!(gl > 0) || !isfinite(gl))
                return false; /* the rim runs through a singular point */
            double nu[3] = {g[0] / gl, g[1] / gl, g[2] / gl}, m[3] = {-nu[0], -nu[1], -nu[2]};
            samples_along(p, nu, clearance, x, y, z, n);
            samples_along(p, m, clearance, x, y, z, n + CLEAR_SAMPLES);
            n += 2 * CLEAR_SAMPLES;
            if (n == ISM_EVAL_BATCH) {
                if (!batch_clear(c, x, y, z, v, n))
                    return false;
                n = 0;
            }
        }
    return n == 0 || batch_clear(c, x, y, z, v, n);
}

bool cf_cut_clean(cf_ctx *c, const cf_cutter *cut, double *radius, double max_radius,
                  cf_loops *ls, uint32_t **removed, size_t *nremoved)
{
    if (*radius > max_radius)
        *radius = max_radius;
    memset(ls, 0, sizeof *ls);
    *removed = NULL;
    *nremoved = 0;
    for (int k = 0;; k++) {
        bool ok = cut_more(c, cut, removed, nremoved) && rim_loops(c, removed, nremoved, ls);
        bool clear = ok && (k == CF_MAX_GROW || ls->n == 0 || *radius * CF_GROW > max_radius ||
                            cf_rim_clear(c, ls, CF_CLEAR_CELLS * c->cell));
        if (!ok || c->stopped) { /* out of memory, or stopped: nothing cut */
            cf_undo(c, *removed, *nremoved, c->m->ntris, c->m->nverts);
            cf_loops_free(ls);
            free(*removed);
            *removed = NULL;
            *nremoved = 0;
            return ok;
        }
        if (clear)
            return true;
        cf_loops_free(ls); /* wider: the removed triangles stay removed */
        *radius *= CF_GROW;
        c->st->cuts_widened++;
    }
}
