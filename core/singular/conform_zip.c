/* conform_zip.c — refilling the tube cut around double curves: each rim loop (one per side
 * of each sheet) gets rings of vertices projected onto f = 0 between it and its foot points
 * on the curve, and its innermost row is zipped to the curve's vertices by arclength, so each
 * curve edge receives one triangle from every sheet side: four where two sheets cross.
 *
 *   row   a0 ─── a1 ────── a2 ── a3        merge by parameter along the curve:
 *          │ ╲    │ ╲       ╱│ ╲  │          advance the row:   (a_i, a_i+1, c_j)
 *   curve c0 ─── c1 ─── c2 ──── c3           advance the curve: (a_i, c_j+1, c_j)
 *
 * Parameters are "unfolded" so that one merge covers a whole loop: along a closed curve they
 * wrap with period L (a loop winding once round it is zipped cyclically); along an open curve
 * they reflect at its ends with period 2L, so a rim that runs up one side of a double segment,
 * round its end (a pinch point, where the sheets fold into each other) and back down the other
 * side is zipped in one pass, each side getting its own triangles on the last curve edge:
 *
 *      unfolded   0 ──────── L ──────── 2L        curve index j, then 2(n−1) − j
 *      curve     c0 ─ … ─ c(n−1) ─ … ─ c0
 *
 * A rim may go round a closed curve more than once (the figure-8 Klein bottle's sheets swap
 * sides along its double circle: two rims, each twice round). A loop that does not turn at an
 * end of its curve is split at its extreme parameters into
 * runs, each zipped to the stretch of curve it spans, its ends taken to an end of the curve
 * within END_SNAP_RHO (box exits, junctions of curves). */
#include "core/singular/conform_internal.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>

/* The rim lies about rho from the curve; its feet are searched this many rho away first.
 * A rim vertex can lie farther: the tube takes every triangle that comes within rho, and
 * where the octree is coarse beside the curve (a sphere's flat top next to the circle where
 * it crosses another, 3 finest cells off) such a triangle reaches 5 rho away. Its foot is
 * then searched without bound (the polyline's widening search costs little): fanning the
 * whole rim to its centroid instead (the last resort) would span the sphere. */
#define FOOT_SEARCH_RHO 4.0
/* A run's end parameter this many rho from an end of an open curve is taken to that end,
 * and a loop whose extreme parameter is that close turns round that end: the tube's rounded
 * cap (a box exit, a pinch point, a junction of curves, where a rim vertex on the bisector of
 * two curves lies about rho along each). */
#define END_SNAP_RHO 2.0
/* A chain whose extreme parameter near an end of its curve exceeds both its own ends by this
 * many rho turns round that end (a rim's parameters wiggle by less along a tube's side). */
#define TURN_MIN_RHO 0.25

/* Index steps in one period of the unfolded curve. */
static long period_steps(const cf_polyline *pl)
{
    return pl->closed ? (long)pl->n : 2 * ((long)pl->n - 1);
}

static double period_length(const cf_polyline *pl)
{
    return pl->closed ? pl->length : 2 * pl->length;
}

static long floor_div(long a, long b)
{
    return a >= 0 ? a / b : -((-a + b - 1) / b);
}

/* The curve point of unfolded index J, and J's unfolded parameter. */
static size_t fold_index(const cf_polyline *pl, long J, double *param)
{
    long P = period_steps(pl), w = floor_div(J, P), k = J - w * P;
    double base = (double)w * period_length(pl);
    if (pl->closed || k <= (long)pl->n - 1) {
        *param = base + pl->s[k];
        return (size_t)k % pl->n;
    }
    k = P - k; /* the way back along an open curve */
    *param = base + 2 * pl->length - pl->s[k];
    return (size_t)k;
}

static double curve_param(const cf_polyline *pl, long J)
{
    double p;
    fold_index(pl, J, &p);
    return p;
}

static uint32_t curve_vertex(const cf_polyline *pl, const uint32_t *cv, long J)
{
    double p;
    return cv[fold_index(pl, J, &p)];
}

/* A row vertex is at a pinch point's parameter when nearer it than this share of the gap to
 * the curve's next vertex (nearer the pinch point than that vertex). */
#define PINCH_NEAR_GAP 0.5

/* Unfolded curve index J is a pinch end of the curve. */
static bool at_pinch(const cf_polyline *pl, long J)
{
    double p;
    size_t k = fold_index(pl, J, &p);
    return !pl->closed && ((k == 0 && pl->pinch[0]) || (k == pl->n - 1 && pl->pinch[1]));
}

/* The index among s[0..top] whose parameter is nearest x. */
static long nearest_point(const cf_polyline *pl, size_t top, double x)
{
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
    return (long)lo;
}

/* Turns a rim may make round a curve, at most: a rim winds a closed curve a few times (the
 * Klein bottle's twice); anything past this is a broken parameter, not a winding. */
#define CF_MAX_PERIODS 1e6

/* The unfolded curve index whose parameter is nearest the unfolded parameter x. */
static long curve_index_near(const cf_polyline *pl, double x)
{
    double per = period_length(pl), w = per > 0 ? floor(x / per) : 0.0;
    /* A curve of zero length or a parameter that is not finite has no period to count:
     * the first one (converting such a w to long would be undefined). */
    if (!(fabs(w) <= CF_MAX_PERIODS))
        w = 0.0;
    double y = x - w * per;
    long base = (long)w * period_steps(pl);
    if (pl->closed)
        return base + nearest_point(pl, pl->n, y);
    if (y <= pl->length)
        return base + nearest_point(pl, pl->n - 1, y);
    return base + period_steps(pl) - nearest_point(pl, pl->n - 1, 2 * pl->length - y);
}

/* zip_seq through the loop's graded rows (conform_grade.c): 1 done, 0 out of memory, -1 the
 * stretch cannot be graded (no length, or it turns round an end of its curve). */
static int grade_seq(cf_ctx *c, const cf_polyline *pl, const uint32_t *cv, const uint32_t *row,
                     const double *U, size_t len, long Ja, long Jb, int dir)
{
    size_t nb = (size_t)labs(Jb - Ja) + 1;
    uint32_t *bot = malloc(nb * sizeof *bot);
    double *bx = malloc(nb * sizeof *bx), *tx = malloc(len * sizeof *tx);
    int ret = 0;
    if (!bot || !bx || !tx)
        goto done;
    ret = -1;
    for (size_t j = 0; j < nb; j++) {
        long J = Ja + dir * (long)j;
        double p;
        size_t k = fold_index(pl, J, &p);
        /* a fold inside: the rows would cross the end of the curve between its sheets */
        if (!pl->closed && j > 0 && j + 1 < nb && (k == 0 || k == pl->n - 1))
            goto done;
        bot[j] = cv[k];
        bx[j] = dir * p;
    }
    for (size_t i = 0; i < len; i++) /* the row's keys, made monotone (as zip_seq's) */
        tx[i] = i ? fmax(tx[i - 1], dir * U[i]) : dir * U[0];
    ret = cf_grade_strip(c, c->grade, row, tx, len, bot, bx, nb);
done:
    free(bot);
    free(bx);
    free(tx);
    return ret;
}

/* Zips row[0..len) (unfolded parameters U) to the curve's unfolded indices Ja .. Jb. */
static bool zip_seq(cf_ctx *c, const cf_polyline *pl, const uint32_t *cv, const uint32_t *row,
                    const double *U, size_t len, long Ja, long Jb)
{
    int dir = Jb > Ja || (Jb == Ja && U[len - 1] >= U[0]) ? 1 : -1;
    if (c->grade && c->grade->refused)
        return true; /* the loop is zipped again straight: grading the rest is wasted */
    if (c->grade) {
        int g = grade_seq(c, pl, cv, row, U, len, Ja, Jb, dir);
        if (g < 0)
            c->grade->refused = true; /* the loop is zipped again without */
        return g != 0;
    }
    size_t i = 0, m = len - 1;
    long J = Ja;
    double key = dir * U[0]; /* the row's keys, made monotone */
    bool curve_moved = false;
    while (i < m || J != Jb) {
        bool adv_row = J == Jb || (i < m && fmax(key, dir * U[i + 1]) <= dir * curve_param(pl, J + dir));
        /* round a fold with one row vertex the next triangle would repeat the last one
         * backwards (a, c_j−1, c_j) after (a, c_j, c_j−1): the row moves first */
        if (!adv_row && i < m && curve_moved &&
            curve_vertex(pl, cv, J + dir) == curve_vertex(pl, cv, J - dir))
            adv_row = true;
        /* a row vertex at a pinch point's parameter (nearer it than the curve's vertex before:
         * the rim's cap round the curve's end, on the fold between the sheets) is reached
         * from the pinch point: the curve's vertices before it go to the row's vertex on the
         * sheet they lie on (fanned from the vertex on the fold, their triangles spanned the
         * two sheets: cross-cap, depth 6, centroids 0.27 cells off f = 0 by |f| / |∇f| beside
         * its pinch point at (0, 0, 1), twice the farthest elsewhere) */
        if (adv_row && J != Jb && i < m && at_pinch(pl, J + dir) &&
            fabs(U[i + 1] - curve_param(pl, J + dir)) <
                PINCH_NEAR_GAP * fabs(curve_param(pl, J + dir) - curve_param(pl, J)))
            adv_row = false;
        uint32_t cj = curve_vertex(pl, cv, J);
        if (adv_row) {
            key = fmax(key, dir * U[i + 1]);
            if (!cf_add_triangle(c, row[i], row[i + 1], cj))
                return false;
            i++;
        } else {
            if (!cf_add_triangle(c, row[i], curve_vertex(pl, cv, J + dir), cj))
                return false;
            J += dir;
        }
        curve_moved = !adv_row;
    }
    return true;
}

/* An open stretch: an end parameter within ext of a fold (an end of an open curve) beyond
 * it is taken there — the stretch grows to the curve's end, never shrinks towards it. */
static bool zip_open_seq(cf_ctx *c, const cf_polyline *pl, const uint32_t *cv,
                         const uint32_t *row, double *U, size_t len, double ext)
{
    if (!pl->closed && len > 1) {
        double L = pl->length, *first = &U[0], *last = &U[len - 1];
        bool up = *last >= *first;
        double a = (up ? floor(*first / L) : ceil(*first / L)) * L;
        double b = (up ? ceil(*last / L) : floor(*last / L)) * L;
        if (fabs(*first - a) < ext)
            *first = a;
        if (fabs(*last - b) < ext)
            *last = b;
    }
    return zip_seq(c, pl, cv, row, U, len, curve_index_near(pl, U[0]),
                   curve_index_near(pl, U[len - 1]));
}

/* The loop's rings (rings of the vertices beside a pinch point in its chart; u[i] then
 * becomes the parameter of the innermost ring's vertex, and moved[i], when moved is not
 * NULL, says so), scaled from the rim points (cf_pinch_rim_points). */
static uint32_t *make_rows(cf_ctx *c, const cf_loop *l, const double *foot, const cf_polyline *pl,
                           const cf_pinch *ends, const int *cid, double *u, double rho,
                           bool *moved)
{
    const cf_pinch **ch = malloc(l->n * sizeof *ch);
    double *q = malloc(3 * l->n * sizeof *q);
    bool *on_fold = malloc(l->n * sizeof *on_fold);
    uint32_t *rows = NULL;
    if (!ch || !q || !on_fold)
        goto done;
    for (size_t i = 0; i < l->n; i++)
        ch[i] = cf_pinch_near(ends, pl, cid[i], u[i], CF_PINCH_REACH_RHO * rho);
    if (!cf_pinch_rim_points(c, l, ch, q, on_fold))
        goto done;
    double width = 0;
    for (size_t i = 0; i < l->n; i++)
        width += ism_dist3(q + 3 * i, foot + 3 * i) / (double)l->n;
    int rings = cf_ring_count(width, cf_loop_mean_edge(c, l));
    if (!(rows = malloc(2 * l->n * sizeof *rows)))
        goto done;
    uint32_t *outer = rows, *inner = rows + l->n;
    for (size_t i = 0; i < l->n; i++)
        outer[i] = l->v[i];
    for (int r = rings; r >= 1 && !c->stopped; r--) {
        double t = (double)r / (rings + 1);
        for (size_t i = 0; i < l->n; i++) {
            const double *v = q + 3 * i, *ft = foot + 3 * i;
            double p[3];
            cf_grad kept = {.at = false};
            if (ch[i]) {
                cf_pinch_ring_point(c, ch[i], v, t, p);
            } else {
                for (int k = 0; k < 3; k++)
                    p[k] = ft[k] + t * (v[k] - ft[k]);
                cf_project_keep(c, p, 0.5 * t * ism_dist3(v, ft), &kept);
            }
            /* a ring on the fold (cf_pinch_rim_points) stays there (pinned): its vertex
             * normals (∇f along the curve's tangent) are square to both sheets' triangles,
             * and the untangling read those as turned and moved its vertices onto a sheet,
             * which joined the two sheets again (Steiner, depth 5, +1e-3 box, conform/
             * steiner_roman_pinch_and_triple_points: a centroid 0.31 cell off f = 0 beside a
             * pinch point, 0.20 pinned and 0.25 before the rings on the fold) */
            inner[i] = cf_add_vertex_kept(c, p, on_fold[i] ? CF_VERTEX_PINNED : 0, &kept);
            if (inner[i] == CF_NONE) {
                free(rows);
                rows = NULL;
                goto done;
            }
            c->st->vertices_added++;
        }
        if (!cf_ladder(c, outer, inner, l->n, l->closed)) {
            free(rows);
            rows = NULL;
            goto done;
        }
        uint32_t *t2 = outer;
        outer = inner;
        inner = t2;
    }
    for (size_t i = 0; i < l->n; i++) {
        rows[i] = outer[i]; /* innermost first */
        /* a ring vertex moved along the tangent (onto the fold, beside a pinch point) is
         * zipped by where it went */
        bool mv = ch[i] && rings > 0;
        if (moved)
            moved[i] = mv;
        if (mv)
            u[i] = cf_pinch_param(ch[i], &pl[cid[i]], c->m->pos + 3 * (size_t)outer[i]);
    }
done:
    free((void *)ch);
    free(q);
    free(on_fold);
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

/* Turns of the parameter sequence u[0..N) (a zigzag with hysteresis m): turn[k] is the index
 * of the k-th extreme, up[k] whether it is a maximum. Returns their number. */
static size_t find_turns(const double *u, size_t N, double m, size_t *turn, bool *up)
{
    size_t nt = 0, ext = 0, lo = 0, hi = 0;
    int dir = 0;
    for (size_t i = 1; i < N; i++) {
        if (dir == 0) {
            hi = u[i] > u[hi] ? i : hi;
            lo = u[i] < u[lo] ? i : lo;
            if (u[hi] - u[lo] <= m)
                continue;
            dir = hi > lo ? 1 : -1;
            size_t first = dir > 0 ? lo : hi; /* an extreme before the first real move */
            if (first > 0 && fabs(u[first] - u[0]) > m) {
                up[nt] = dir < 0;
                turn[nt++] = first;
            }
            ext = dir > 0 ? hi : lo;
        } else if ((u[i] - u[ext]) * dir > 0) {
            ext = i;
        } else if ((u[ext] - u[i]) * dir > m) {
            up[nt] = dir > 0;
            turn[nt++] = ext;
            dir = -dir;
            ext = i;
        }
    }
    return nt;
}

/* A turn near the end of the open curve it points to: the rim goes round that end (a pinch
 * point) rather than turning away from the curve. */
static bool is_fold(const cf_polyline *pl, double u, bool up, double ext)
{
    return up ? u > pl->length - ext : u < ext;
}

/* Zips row/u[0..N) along an open curve: split into runs at turns away from the curve's ends,
 * unfolded at turns round them (U = base + sigma u, reflected at each fold). cyclic: the
 * sequence's last vertex is its first, and it starts at a fold at the curve's start. */
static bool zip_open_curve(cf_ctx *c, const cf_polyline *pl, const uint32_t *cv,
                           const uint32_t *row, const double *u, size_t N, double rho,
                           bool cyclic, double *U, size_t *turn, bool *up)
{
    double ext = END_SNAP_RHO * rho, L = pl->length;
    size_t nt = find_turns(u, N, TURN_MIN_RHO * rho, turn, up), rs = 0, k = 0;
    bool any_split = false;
    for (size_t t = 0; t < nt; t++)
        any_split |= !is_fold(pl, u[turn[t]], up[t], ext);
    if (cyclic && !any_split) { /* round a double segment, k times over its unfolded cycle */
        double base = 0, sigma = 1;
        for (size_t i = 0; i < N; i++) {
            U[i] = base + sigma * u[i];
            if (k < nt && turn[k] == i) {
                double end = up[k] ? L : 0;
                base += 2 * sigma * end;
                sigma = -sigma;
                k++;
            }
        }
        long cycles = lround(U[N - 1] / (2 * L));
        if (cycles >= 1) {
            U[0] = 0;
            U[N - 1] = (double)cycles * 2 * L;
            return zip_seq(c, pl, cv, row, U, N, 0, cycles * period_steps(pl));
        }
    }
    bool ok = true;
    while (ok && rs < N - 1) {
        /* one run: from rs to the next split (or the end), unfolded at the folds between */
        size_t re = N - 1, kk = k;
        while (kk < nt && turn[kk] <= rs)
            kk++;
        k = kk;
        for (; kk < nt; kk++)
            if (!is_fold(pl, u[turn[kk]], up[kk], ext)) {
                re = turn[kk];
                break;
            }
        size_t probe = k < nt && turn[k] < re ? turn[k] : re;
        double sigma = u[probe] >= u[rs] ? 1 : -1, base = 0;
        if (k < nt && turn[k] < re && u[probe] == u[rs])
            sigma = up[k] ? 1 : -1;
        for (size_t i = rs; i <= re; i++) {
            U[i - rs] = base + sigma * u[i];
            if (k < nt && turn[k] == i && i != re) {
                base += 2 * sigma * (up[k] ? L : 0);
                sigma = -sigma;
                k++;
            }
        }
        ok = zip_open_seq(c, pl, cv, row + rs, U, re - rs + 1, ext);
        rs = re;
    }
    return ok;
}

/* Rotates the closed loop's row and parameters to start at index s, closing it by repeating
 * that vertex at the end. */
static void rotate(const uint32_t *row_in, const double *u, size_t n, size_t s, uint32_t *row,
                   double *v)
{
    for (size_t i = 0; i <= n; i++) {
        row[i] = row_in[(s + i) % n];
        v[i] = u[(s + i) % n];
    }
}

static bool zip_loop(cf_ctx *c, const cf_polyline *pl, const uint32_t *cv, const cf_loop *l,
                     double *u, const uint32_t *row_in, double rho)
{
    size_t n = l->n;
    double L = pl->length;
    uint32_t *row = malloc((n + 1) * sizeof *row);
    double *U = malloc((n + 1) * sizeof *U), *v = malloc((n + 1) * sizeof *v);
    size_t *turn = malloc((n + 1) * sizeof *turn);
    bool *up = malloc((n + 1) * sizeof *up), ok = row && U && v && turn && up;
    if (!ok)
        goto done;
    long wind = unwrap(pl, l, u);
    size_t imin = argext(u, n, -1), imax = argext(u, n, 1);
    if (wind != 0) { /* round a closed curve: one cyclic run, |wind| times round (twice on
                        a Klein bottle, whose sheets swap sides along the curve) */
        rotate(row_in, u, n, 0, row, U);
        U[n] = u[0] + (double)wind * L;
        long Ja = curve_index_near(pl, u[0]);
        ok = zip_seq(c, pl, cv, row, U, n + 1, Ja, Ja + wind * (long)pl->n);
    } else if (pl->closed && l->closed) { /* a closed loop beside a stretch: split at extremes */
        size_t a = (imax + n - imin) % n + 1, b = (imin + n - imax) % n + 1;
        rotate(row_in, u, n, imin, row, U);
        ok = zip_open_seq(c, pl, cv, row, U, a, 0);
        rotate(row_in, u, n, imax, row, U);
        ok = ok && zip_open_seq(c, pl, cv, row, U, b, 0);
    } else if (pl->closed) {
        ok = zip_open_seq(c, pl, cv, row_in, u, n, 0);
    } else if (l->closed) { /* from the global minimum round to it again */
        rotate(row_in, u, n, imin, row, v);
        bool cyclic = v[0] < END_SNAP_RHO * rho;
        if (cyclic) { /* a split elsewhere: start there instead, the minimum is a fold */
            size_t nt = find_turns(v, n + 1, TURN_MIN_RHO * rho, turn, up);
            for (size_t t = 0; t < nt; t++)
                if (!is_fold(pl, v[turn[t]], up[t], END_SNAP_RHO * rho)) {
                    rotate(row_in, u, n, (imin + turn[t]) % n, row, v);
                    cyclic = false;
                    break;
                }
        }
        ok = zip_open_curve(c, pl, cv, row, v, n + 1, rho, cyclic, U, turn, up);
    } else {
        ok = zip_open_curve(c, pl, cv, row_in, u, n, rho, false, U, turn, up);
    }
done:
    free(row);
    free(U);
    free(v);
    free(turn);
    free(up);
    return ok;
}

/* Nearest curve of the group to p: its index (or -1 when none lies within reach), the
 * parameter and the foot. */
static int nearest_curve(const cf_polyline *pl, size_t npl, const double p[3], double reach,
                         double *u, double foot[3])
{
    int best = -1;
    double bd = INFINITY, mag = fmax(fabs(p[0]), fmax(fabs(p[1]), fabs(p[2])));
    for (size_t k = 0; k < npl; k++) {
        /* a curve whose box is farther than the nearest so far can be neither nearer nor
         * as near (the first of equals is kept) */
        if (isfinite(bd) && cf_polyline_box_distance(&pl[k], p) > bd + CF_QUERY_SLACK * (bd + mag))
            continue;
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

/* The parameter on curve k of the end it shares with curve j (the one nearer p when both
 * ends are shared), or NAN when they share none (or j is no other curve). */
static double shared_end(const cf_polyline *pl, const uint32_t *const *cv, int k, int j,
                         const double p[3])
{
    if (j < 0 || j == k || pl[k].closed || pl[j].closed)
        return NAN;
    double best = NAN, bd = INFINITY;
    for (int e = 0; e < 2; e++) {
        size_t ik = e ? pl[k].n - 1 : 0;
        uint32_t v = cv[k][ik];
        if (v != cv[j][0] && v != cv[j][pl[j].n - 1])
            continue;
        double d = ism_dist3(p, pl[k].p + 3 * ik);
        if (d < bd) {
            bd = d;
            best = e ? pl[k].length : 0.0;
        }
    }
    return best;
}

/* A loop along several curves of a group (they meet at junctions): split into runs of
 * vertices nearest the same curve (consecutive runs share their boundary vertex), each
 * zipped to its curve as an open loop. Where the curves of two consecutive runs share an
 * end (a junction), the boundary vertex is zipped to that end from both runs: it lies in the
 * corner between them, and a parameter snapped there (END_SNAP_RHO) from one run only left
 * the other run's stretch from the junction without triangles — nine planes at depth 4 in
 * the 0.37-cell box: the corner's rim vertex lay 1.55 ρ from one axis and 2.003 ρ along the
 * other, and the triangle beside the triple point at the origin was missing (χ 8 for 9). */
static bool zip_multi(cf_ctx *c, const cf_polyline *pl, const uint32_t *const *cv,
                      const cf_loop *l, const int *cid, const uint32_t *row, double rho,
                      const double *uring, const bool *moved)
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
            /* a ring vertex moved along the tangent beside a pinch point (make_rows) is
             * zipped by where it went, as in zip_loop: its rim's foot lay 0.38 cell
             * farther from the pinch (Steiner, depth 9, irrational box: two ring vertices
             * 8.6e-5 apart at 0.0011 from (−1/2, 0, 0) read 0.0026, past the curve
             * vertex at 0.00258, and were fanned to the one at 0.0058 across their own
             * slanted edge: one edge turned over) */
            if (moved[i] && cid[i] == k)
                u[j] = uring[i];
        }
        int prev = l->closed || done > 0 ? cid[(i0 + n - 1) % n] : -1;
        int next = cid[(i0 + len - 1) % n];
        double a = shared_end(pl, cv, k, prev, c->m->pos + 3 * (size_t)v[0]);
        double b = shared_end(pl, cv, k, next, c->m->pos + 3 * (size_t)v[len - 1]);
        if (!isnan(a))
            u[0] = a;
        if (!isnan(b))
            u[len - 1] = b;
        cf_loop sub = {v, len, false};
        ok = feet ? zip_loop(c, &pl[k], cv[k], &sub, u, rw, rho) : cf_fan_centroid(c, &sub);
        done += len - 1;
    }
    free(v);
    free(rw);
    free(u);
    return ok;
}

/* The feet of a loop along several curves where it passes from one curve's run to the next
 * (the first vertex of each run, zip_multi's boundary vertex) and the two curves share an
 * end (a junction: a triple point): that end. The rim there turns the corner between the two
 * tubes, about as far from both curves, and its rings are drawn towards the junction —
 * towards one curve's foot, the corner's ring vertex fell in line with the rim beside it and
 * the ladder quad there stood on edge (Steiner's surface, depth 7: 18 edges turned over in
 * every box at the six corners between two axes, 10 cells from the triple point). */
static void junction_feet(const cf_ctx *c, const cf_polyline *pl, const uint32_t *const *cv,
                          const cf_loop *l, const int *cid, double *foot)
{
    size_t n = l->n;
    for (size_t i = l->closed ? 0 : 1; i < n; i++) {
        int k = cid[i], j = cid[(i + n - 1) % n];
        double a = shared_end(pl, cv, k, j, c->m->pos + 3 * (size_t)l->v[i]);
        if (isnan(a))
            continue;
        const double *e = pl[k].p + 3 * (a > 0 ? pl[k].n - 1 : 0);
        for (int d = 0; d < 3; d++)
            foot[3 * i + d] = e[d];
    }
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

/* The rows the loop's row is graded toward its curve by (0: zipped straight). Not near a
 * pinch point: there the rows are made in the umbrella's chart and the zip turns round the
 * curve's end between the sheets (conform_pinch.c). The row's spacing is its mean edge, its
 * width its vertices' mean distance to their feet, the curve's spacing the mean of its
 * vertices' curves' edges. */
static int loop_grade_rows(const cf_ctx *c, const cf_polyline *pl, const cf_pinch *ends,
                           const cf_loop *l, const uint32_t *row, const int *cid,
                           const double *u, const double *foot, double rho)
{
    double width = 0, curve_edge = 0;
    for (size_t i = 0; i < l->n; i++) {
        const cf_polyline *p = &pl[cid[i]];
        if (cf_pinch_near(ends, pl, cid[i], u[i], CF_PINCH_REACH_RHO * rho))
            return 0;
        size_t segs = p->closed ? p->n : p->n - 1;
        curve_edge += (segs ? p->length / (double)segs : 0.0) / (double)l->n;
        width += ism_dist3(c->m->pos + 3 * (size_t)row[i], foot + 3 * i) / (double)l->n;
    }
    cf_loop r = {(uint32_t *)row, l->n, l->closed};
    return cf_grade_rows(cf_loop_mean_edge(c, &r), curve_edge, width);
}

/* Zips the loop's row to its curves (zip_multi or zip_loop), through `rows` graded rows
 * (conform_grade.c) when rows > 0 (a copy of u zipped); where a stretch refuses them, the
 * loop is zipped again straight (u unwrapped in place, as ever). False when out of memory. */
static bool zip_graded(cf_ctx *c, const cf_polyline *pl, const uint32_t *const *cv,
                       const cf_loop *l, const int *cid, const uint32_t *row, double rho,
                       double *u, const bool *moved, bool multi, int rows)
{
    cf_grade g;
    cf_grade_init(&g, rows);
    size_t nt0 = c->m->ntris, nv0 = c->m->nverts, added0 = c->st->vertices_added;
    bool ok = true;
    for (int pass = rows > 0 ? 0 : 1; ok && pass < 2; pass++) {
        c->grade = pass == 0 ? &g : NULL;
        double *uz = u; /* zip_loop unwraps u in place: the second pass reads it again */
        if (pass == 0 && !(uz = malloc(l->n * sizeof *uz)))
            ok = false;
        for (size_t i = 0; ok && uz != u && i < l->n; i++)
            uz[i] = u[i];
        ok = ok && (multi ? zip_multi(c, pl, cv, l, cid, row, rho, uz, moved)
                          : zip_loop(c, &pl[cid[0]], cv[cid[0]], l, uz, row, rho));
        if (uz != u)
            free(uz);
        c->grade = NULL;
        if (!ok || !g.refused || c->stopped)
            break;
        cf_truncate(c, nt0, nv0); /* a stretch refused: the loop straight to its curve */
        c->st->vertices_added = added0;
    }
    cf_grade_free(&g);
    return ok;
}

bool cf_zip_loops(cf_ctx *c, const cf_polyline *pl, const uint32_t *const *cv, size_t npl,
                  const cf_loops *ls, double rho)
{
    cf_pinch *ends = malloc(2 * npl * sizeof *ends);
    if (!ends)
        return false;
    cf_pinch_ends(c, pl, npl, rho, ends);
    for (size_t k = 0; k < ls->n && !c->stopped; k++) {
        const cf_loop *l = &ls->l[k];
        double *u = malloc(l->n * sizeof *u), *foot = malloc(3 * l->n * sizeof *foot);
        int *cid = malloc(l->n * sizeof *cid);
        bool found = u && foot && cid, ok = found, multi = false;
        for (size_t i = 0; found && i < l->n; i++) {
            const double *p = c->m->pos + 3 * (size_t)l->v[i];
            cid[i] = nearest_curve(pl, npl, p, FOOT_SEARCH_RHO * rho, &u[i], foot + 3 * i);
            if (cid[i] < 0) /* the corner of a long triangle the tube took (below) */
                cid[i] = nearest_curve(pl, npl, p, INFINITY, &u[i], foot + 3 * i);
            found = cid[i] >= 0;
            multi |= cid[i] != cid[0];
        }
        cf_loop own = {NULL, 0, false}; /* a copy the ears are clipped from */
        if (ok && found) {
            /* the winding round a closed curve (0 along an open one, or several) */
            long wind = multi ? 0 : unwrap(&pl[cid[0]], l, u);
            own = (cf_loop){malloc(l->n * sizeof *own.v), l->n, l->closed};
            ok = own.v != NULL;
            for (size_t i = 0; ok && i < l->n; i++)
                own.v[i] = l->v[i];
            if (multi)
                smooth_ids(cid, l->n, l->closed);
            if (ok && cf_pinch_ears(c, ends, pl, &own, u, foot, cid, CF_PINCH_REACH_RHO * rho,
                                    rho) < 0)
                ok = false;
            if (ok && cf_clip_ears(c, multi ? pl : &pl[cid[0]], &own, u, foot,
                                   multi ? cid : NULL, (int)wind, 0) < 0)
                ok = false;
            l = &own;
        }
        if (ok && !found) {
            ok = cf_fan_centroid(c, l);
        } else if (ok) {
            if (multi)
                junction_feet(c, pl, cv, l, cid, foot);
            /* every loop's rings beside a pinch point are made in its chart (a loop along
             * several curves too, zipped by its rim's feet: each of Steiner's four loops
             * passes three pinch points), those below a rim edge across the fold on it */
            bool *moved = multi ? calloc(l->n ? l->n : 1, sizeof *moved) : NULL; /* zip_multi */
            uint32_t *row = !multi || moved
                                ? make_rows(c, l, foot, pl, ends, cid, u, rho, moved)
                                : NULL;
            ok = row && zip_graded(c, pl, cv, l, cid, row, rho, u, moved, multi,
                                   loop_grade_rows(c, pl, ends, l, row, cid, u, foot, rho));
            free(row);
            free(moved);
        }
        free(own.v);
        free(u);
        free(foot);
        free(cid);
        if (!ok) {
            free(ends);
            return false;
        }
    }
    free(ends);
    return true;
}
