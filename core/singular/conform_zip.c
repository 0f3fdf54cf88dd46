/* conform_zip.c — refilling the tube cut around a double curve: each rim loop (one per side
 * of each sheet) gets rings of vertices projected onto f = 0 between it and its foot points
 * on the curve, and its innermost row is zipped to the curve's vertices by arclength, so each
 * curve edge receives one triangle from every sheet side: four where two sheets cross.
 *
 *   row   a0 ─── a1 ────── a2 ── a3        merge by parameter along the curve:
 *          │ ╲    │ ╲       ╱│ ╲  │          advance the row:   (a_i, a_i+1, c_j)
 *   curve c0 ─── c1 ─── c2 ──── c3           advance the curve: (a_i, c_j+1, c_j)
 *
 * A rim loop that winds once around a closed curve is zipped cyclically; any other loop is
 * split at its extreme parameters into runs that are each zipped to the stretch of curve
 * they span (extended to an end of an open curve within the tube's radius: box exits, pinch
 * points). */
#include "core/singular/conform_internal.h"

#include <math.h>
#include <stdlib.h>

/* The rim lies about rho from the curve; its feet are searched this many rho away. */
#define FOOT_SEARCH_RHO 4.0
/* A run's end parameter this many rho from an end of an open curve is taken to that end:
 * the tube's rounded cap (a box exit, a pinch point, a junction of curves, where a rim
 * vertex on the bisector of two curves lies about rho along each). */
#define END_SNAP_RHO 2.0

typedef struct zip_run {
    const uint32_t *row;  /* the innermost row of the whole loop */
    const double *u;      /* unwrapped parameters of the row */
    size_t n;             /* row length */
    size_t first, len;    /* the run: row[(first + i) % n], i < len */
    double end_shift;     /* added to u of the run's last vertex (a cyclic run's L) */
} zip_run;

static double dist(const double *a, const double *b)
{
    double d0 = a[0] - b[0], d1 = a[1] - b[1], d2 = a[2] - b[2];
    return sqrt(d0 * d0 + d1 * d1 + d2 * d2);
}

/* Parameter of unwrapped curve index J (closed curves wrap with period length). */
static double curve_param(const cf_polyline *pl, long J)
{
    if (!pl->closed)
        return pl->s[J];
    long n = (long)pl->n, w = J >= 0 ? J / n : -((-J + n - 1) / n);
    return pl->s[J - w * n] + (double)w * pl->length;
}

/* The unwrapped curve index whose parameter is nearest x. */
static long curve_index_near(const cf_polyline *pl, double x)
{
    double w = 0;
    size_t top = pl->closed ? pl->n : pl->n - 1;
    if (pl->closed) {
        w = floor(x / pl->length);
        x -= w * pl->length;
    }
    size_t lo = 0, hi = top;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (pl->s[mid] < x)
            lo = mid + 1;
        else
            hi = mid;
    }
    if (lo > 0 && x - pl->s[lo - 1] < pl->s[lo] - x)
        lo--;
    return (long)lo + (long)w * (long)pl->n;
}

static uint32_t curve_vertex(const cf_polyline *pl, const uint32_t *cv, long J)
{
    long n = (long)pl->n;
    return cv[((J % n) + n) % n];
}

static double run_u(const zip_run *r, size_t i)
{
    return r->u[(r->first + i) % r->n] + (i == r->len - 1 ? r->end_shift : 0);
}

/* Zips one run to the curve indices Ja .. Jb (stepping towards Jb). */
static bool zip_run_to(cf_ctx *c, const cf_polyline *pl, const uint32_t *cv, const zip_run *r,
                       long Ja, long Jb)
{
    int dir = Jb >= Ja ? 1 : -1;
    if (Ja == Jb) /* a run shorter than a curve edge: lean on the nearer direction */
        dir = run_u(r, r->len - 1) >= run_u(r, 0) ? 1 : -1;
    size_t i = 0, m = r->len - 1;
    long J = Ja;
    double key = -INFINITY; /* the row's keys, made monotone */
    while (i < m || J != Jb) {
        bool adv_row;
        if (i == m)
            adv_row = false;
        else if (J == Jb)
            adv_row = true;
        else {
            double kr = fmax(key, dir * run_u(r, i + 1)), kc = dir * curve_param(pl, J + dir);
            adv_row = kr <= kc;
        }
        uint32_t a = r->row[(r->first + i) % r->n], cj = curve_vertex(pl, cv, J);
        if (adv_row) {
            key = fmax(key, dir * run_u(r, i + 1));
            if (!cf_add_triangle(c, a, r->row[(r->first + i + 1) % r->n], cj))
                return false;
            i++;
        } else {
            if (!cf_add_triangle(c, a, curve_vertex(pl, cv, J + dir), cj))
                return false;
            J += dir;
        }
    }
    return true;
}

/* A run's stretch of curve: nearest indices to its end parameters, extended to an open
 * curve's end within ext. */
static bool zip_open_run(cf_ctx *c, const cf_polyline *pl, const uint32_t *cv, const zip_run *r,
                         double ext)
{
    double ua = run_u(r, 0), ub = run_u(r, r->len - 1);
    if (!pl->closed) {
        double *lo = ua <= ub ? &ua : &ub, *hi = ua <= ub ? &ub : &ua;
        if (*lo < ext)
            *lo = 0;
        if (*hi > pl->length - ext)
            *hi = pl->length;
    }
    return zip_run_to(c, pl, cv, r, curve_index_near(pl, ua), curve_index_near(pl, ub));
}

/* Rings between the rim and the curve, projected; returns the innermost row (the loop's own
 * vertices when no ring is needed). */
static uint32_t *make_rows(cf_ctx *c, const cf_loop *l, const double *foot)
{
    double width = 0;
    for (size_t i = 0; i < l->n; i++)
        width += dist(c->m->pos + 3 * (size_t)l->v[i], foot + 3 * i) / (double)l->n;
    int rings = cf_ring_count(width, cf_loop_mean_edge(c, l));
    uint32_t *rows = malloc(2 * l->n * sizeof *rows);
    if (!rows)
        return NULL;
    uint32_t *outer = rows, *inner = rows + l->n;
    for (size_t i = 0; i < l->n; i++)
        outer[i] = l->v[i];
    for (int r = rings; r >= 1; r--) {
        double t = (double)r / (rings + 1);
        for (size_t i = 0; i < l->n; i++) {
            const double *v = c->m->pos + 3 * (size_t)l->v[i], *q = foot + 3 * i;
            double p[3];
            for (int k = 0; k < 3; k++)
                p[k] = q[k] + t * (v[k] - q[k]);
            cf_project(c, p, 0.5 * t * dist(v, q));
            if ((inner[i] = cf_add_vertex(c, p, false)) == CF_NONE) {
                free(rows);
                return NULL;
            }
            c->st->vertices_added++;
        }
        if (!cf_ladder(c, outer, inner, l->n, l->closed)) {
            free(rows);
            return NULL;
        }
        uint32_t *t2 = outer;
        outer = inner;
        inner = t2;
    }
    for (size_t i = 0; i < l->n; i++)
        rows[i] = outer[i]; /* innermost first */
    return rows;
}

/* Unwrapped parameters along the loop (steps of a closed curve taken the short way round);
 * returns the loop's winding number around a closed curve (0 for an open curve). */
static long unwrap(const cf_polyline *pl, const cf_loop *l, double *u)
{
    if (!pl->closed)
        return 0;
    double L = pl->length;
    for (size_t i = 1; i < l->n; i++) {
        double d = u[i] - u[i - 1];
        u[i] = u[i - 1] + d - L * round(d / L);
    }
    if (!l->closed)
        return 0;
    double d = u[0] - u[l->n - 1];
    double total = u[l->n - 1] + d - L * round(d / L) - u[0];
    return lround(total / L);
}

static size_t argext(const double *u, size_t n, int sign)
{
    size_t k = 0;
    for (size_t i = 1; i < n; i++)
        if (sign * u[i] > sign * u[k])
            k = i;
    return k;
}

static bool zip_loop(cf_ctx *c, const cf_polyline *pl, const uint32_t *cv, const cf_loop *l,
                     const double *u, const uint32_t *row, double rho)
{
    long wind = unwrap(pl, l, (double *)u);
    zip_run r = {row, u, l->n, 0, l->n, 0};
    if (wind == 1 || wind == -1) { /* once round a closed curve: one cyclic run */
        r.len = l->n + 1;
        r.end_shift = (double)wind * pl->length;
        long Ja = curve_index_near(pl, u[0]);
        return zip_run_to(c, pl, cv, &r, Ja, Ja + wind * (long)pl->n);
    }
    if (!l->closed) {
        size_t imin = argext(u, l->n, -1), imax = argext(u, l->n, 1);
        double a = u[0], b = u[l->n - 1];
        size_t split = fmin(a, b) - u[imin] > rho ? imin : u[imax] - fmax(a, b) > rho ? imax : 0;
        if (split == 0 || split == l->n - 1)
            return zip_open_run(c, pl, cv, &r, END_SNAP_RHO * rho);
        r.len = split + 1;
        zip_run r2 = {row, u, l->n, split, l->n - split, 0};
        return zip_open_run(c, pl, cv, &r, END_SNAP_RHO * rho) &&
               zip_open_run(c, pl, cv, &r2, END_SNAP_RHO * rho);
    }
    size_t imin = argext(u, l->n, -1), imax = argext(u, l->n, 1);
    if (imin == imax)
        return cf_fan_centroid(c, l);
    zip_run r1 = {row, u, l->n, imin, (imax + l->n - imin) % l->n + 1, 0};
    zip_run r2 = {row, u, l->n, imax, (imin + l->n - imax) % l->n + 1, 0};
    return zip_open_run(c, pl, cv, &r1, END_SNAP_RHO * rho) &&
           zip_open_run(c, pl, cv, &r2, END_SNAP_RHO * rho);
}

/* Nearest curve of the group to p: its index (or -1 when none lies within reach), the
 * parameter and the foot. */
static int nearest_curve(const cf_polyline *pl, size_t npl, const double p[3], double reach,
                         double *u, double foot[3])
{
    int best = -1;
    double bd = INFINITY;
    for (size_t k = 0; k < npl; k++) {
        double uk, fk[3], d = cf_polyline_nearest(&pl[k], p, reach, &uk, fk);
        if (d < bd) {
            bd = d;
            best = (int)k;
            *u = uk;
            for (int j = 0; j < 3; j++)
                foot[j] = fk[j];
        }
    }
    return best;
}

/* A loop along several curves of a group (they meet at junctions): split into runs of
 * vertices nearest the same curve (consecutive runs share their boundary vertex), each
 * zipped to its curve as an open loop. */
static bool zip_multi(cf_ctx *c, const cf_polyline *pl, const uint32_t *const *cv,
                      const cf_loop *l, const int *cid, const uint32_t *row, double rho)
{
    size_t n = l->n, start = 0;
    if (l->closed) /* begin at a change of curve */
        while (start < n && cid[start] == cid[(start + n - 1) % n])
            start++;
    size_t total = l->closed ? n : n - 1; /* edges to cover */
    uint32_t *v = malloc((n + 1) * sizeof *v), *rw = malloc((n + 1) * sizeof *rw);
    double *u = malloc((n + 1) * sizeof *u), foot[3];
    bool ok = v && rw && u;
    for (size_t done = 0; ok && done < total;) {
        size_t i0 = (start + done) % n, len = 1;
        int k = cid[i0];
        while (done + len < total && cid[(i0 + len) % n] == k)
            len++;
        len++; /* the boundary vertex, shared with the next run */
        bool feet = true;
        for (size_t j = 0; j < len; j++) {
            size_t i = (i0 + j) % n;
            v[j] = l->v[i];
            rw[j] = row[i];
            feet = feet && isfinite(cf_polyline_nearest(&pl[k], c->m->pos + 3 * (size_t)v[j],
                                                        FOOT_SEARCH_RHO * rho, &u[j], foot));
        }
        cf_loop sub = {v, len, false};
        ok = feet ? zip_loop(c, &pl[k], cv[k], &sub, u, rw, rho) : cf_fan_centroid(c, &sub);
        done += len - 1;
    }
    free(v);
    free(rw);
    free(u);
    return ok;
}

/* A vertex claimed by another curve than both its neighbours (which agree) follows them. */
static void smooth_ids(int *cid, size_t n, bool closed)
{
    for (size_t i = 0; i < n; i++) {
        if (!closed && (i == 0 || i == n - 1))
            continue;
        int a = cid[(i + n - 1) % n], b = cid[(i + 1) % n];
        if (a == b && cid[i] != a)
            cid[i] = a;
    }
}

bool cf_zip_loops(cf_ctx *c, const cf_polyline *pl, const uint32_t *const *cv, size_t npl,
                  const cf_loops *ls, double rho)
{
    for (size_t k = 0; k < ls->n; k++) {
        const cf_loop *l = &ls->l[k];
        double *u = malloc(l->n * sizeof *u), *foot = malloc(3 * l->n * sizeof *foot);
        int *cid = malloc(l->n * sizeof *cid);
        bool found = u && foot && cid, ok = found, multi = false;
        for (size_t i = 0; found && i < l->n; i++) {
            cid[i] = nearest_curve(pl, npl, c->m->pos + 3 * (size_t)l->v[i],
                                   FOOT_SEARCH_RHO * rho, &u[i], foot + 3 * i);
            found = cid[i] >= 0;
            multi |= cid[i] != cid[0];
        }
        if (ok && !found) {
            ok = cf_fan_centroid(c, l);
        } else if (ok) {
            uint32_t *row = make_rows(c, l, foot);
            smooth_ids(cid, l->n, l->closed);
            ok = row && (multi ? zip_multi(c, pl, cv, l, cid, row, rho)
                               : zip_loop(c, &pl[cid[0]], cv[cid[0]], l, u, row, rho));
            free(row);
        }
        free(u);
        free(foot);
        free(cid);
        if (!ok)
            return false;
    }
    return true;
}
