/* conform_grade.c — rows graded between a zip's row and its curve: where the tube's innermost
 * row is many curve edges apart (the polygoniser's cells beside flat sheets stay coarse while
 * the curve's vertices are half a finest cell apart), each row vertex zipped straight to the
 * curve fans over tens of curve edges (x y z = 0 in the irrational box: 98) and every one of
 * those triangles is a needle. Rows between them, each twice as coarse as the one below and
 * about as far above it as that row's spacing, make triangles of 38.7° and more but for the
 * last layer, under the loop's row:
 *
 *   row    a0 ───────────── a1 ───────────── a2      the loop's row, t = 1
 *           │ ╲          ╱  │  ╲            ╱ │
 *   row 2  r0 ───── r1 ───── r2 ───── r3 ─── r4      t_2: over every 4th curve vertex
 *           │ ╲   ╱ │ ╲   ╱ │  ╲   ╱ │ ╲   ╱ │
 *   row 1  ...                                       t_1: over every other one
 *   curve  c0 ─ c1 ─ c2 ─ c3 ─ ...                   t = 0, spacing h_c
 *
 * In the strip's chart s ∈ [0, 1] runs along the stretch of curve (its arclength scaled; the
 * row's vertices keyed by their feet on it) and t from the curve (0) to the row (1); a row
 * vertex stands upright over its curve point, t_k of the way to the row there, moved onto
 * f = 0 by Newton along ∇f (at most half its distance to the curve: never onto the other
 * sheet). The strip's two sides (a row vertex above the curve vertex it is zipped to) may be
 * another stretch's side too (a loop split into runs, a loop closed on itself): each side's
 * row vertices are made once (the loop's table of sides) at the loop's fractions t_k, so
 * both stretches end their rows on the same vertices. Consecutive rows are zipped by s, as
 * the row is zipped to the curve (conform_zip.c). */
#include "core/singular/conform_internal.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>

/* Each row twice as coarse as the one below (a row edge over two edges of the row below). */
#define GRADE_RATIO 2.0
/* The rows' gaps over the spacing of the row below, at most and at least (cf_grade_strip):
 * a lower row's vertex under each upper one and one under the middle of each upper edge make
 * angles of atan(β) and atan(1 / β), 38.7° and more within these, over the quality pass's
 * comfort (ISM_RM_COMFORT_DEG, 35°: it leaves such triangles alone). */
#define GRADE_BETA_MIN 0.8
#define GRADE_BETA_MAX 1.25
/* A row coarser than the curve by less than this keeps its zip straight: its fans are of two
 * or three curve edges, as the octree leaves them wherever it refines toward the curve. The
 * octree's levels halve the edge, so a row one level coarser than the curve spans about
 * GRADE_RATIO (2) curve edges an edge, two levels 4: 2.83 is 2√2 rounded, half-way between
 * them in levels (log scale) — a row one level coarser stays straight, one two or more
 * levels coarser is graded, with room for the edges' spread about their level. (c09129c
 * recorded no measurement for the value; the straight fans it leaves are at most 3 curve
 * edges, test_quality.ZipBesideTheDoubleLines.) */
#define GRADE_MIN_RATIO 2.83

int cf_grade_rows(double row_edge, double curve_edge, double width)
{
    if (!(curve_edge > 0) || !(width > 0) || !(row_edge >= GRADE_MIN_RATIO * curve_edge))
        return 0;
    /* rows k = 1 .. K at t_k = (2^k − 1) / (2^(K+1) − 1) of the width (cf_grade_init) lie
     * β h_c 2^(k−1) above the row below, β = width / (h_c (2^(K+1) − 1)): K is the count
     * nearest β = 1, 45° (rows spread over the width at 0.56 of their spacing, 30°, had the
     * quality pass relax every one of them: 1.49 × the polygonisation's instructions,
     * x y z = 0, irrational box; GRADE_BETA_MIN / MAX) */
    long k = lround(log2(width / curve_edge + 1)) - 1;
    return k < 0 ? 0 : k > CF_GRADE_MAX_ROWS ? CF_GRADE_MAX_ROWS : (int)k;
}

void cf_grade_init(cf_grade *g, int rows)
{
    *g = (cf_grade){.rows = rows};
    double top = pow(GRADE_RATIO, rows + 1) - 1;
    for (int k = 0; k <= rows + 1; k++)
        g->t[k] = (pow(GRADE_RATIO, k) - 1) / top;
}

void cf_grade_free(cf_grade *g)
{
    free(g->side);
    g->side = NULL;
    g->nside = g->cap = 0;
}

/* The point t of the way from a to b, moved onto f = 0 (at most half that way from a: its own
 * sheet); its vertex, CF_NONE when out of memory. */
static uint32_t row_vertex(cf_ctx *c, const double a[3], const double b[3], double t)
{
    double p[3];
    for (int k = 0; k < 3; k++)
        p[k] = a[k] + t * (b[k] - a[k]);
    cf_grad kept;
    cf_project_keep(c, p, 0.5 * t * ism_dist3(a, b), &kept);
    uint32_t v = cf_add_vertex_kept(c, p, 0, &kept);
    if (v != CF_NONE)
        c->st->vertices_added++;
    return v;
}

/* The side from row vertex r down to curve vertex cv: its row vertices (rows 1 .. K), made
 * the first time it is asked for. NULL when out of memory. A linear scan of the loop's sides
 * (quadratic in its stretches) is enough: a loop has few stretches, two sides each. */
static const uint32_t *side(cf_ctx *c, cf_grade *g, uint32_t r, uint32_t cv)
{
    for (size_t i = 0; i < g->nside; i++)
        if (g->side[i].r == r && g->side[i].c == cv)
            return g->side[i].v;
    if (!cf_grow((void **)&g->side, &g->cap, g->nside + 1, sizeof *g->side))
        return NULL;
    cf_grade_side *s = &g->side[g->nside];
    s->r = r;
    s->c = cv;
    const double *a = c->m->pos + 3 * (size_t)cv, *b = c->m->pos + 3 * (size_t)r;
    for (int k = 1; k <= g->rows; k++)
        if ((s->v[k] = row_vertex(c, a, b, g->t[k])) == CF_NONE)
            return NULL;
    g->nside++;
    return s->v;
}

/* The point of the polyline v[0 .. n) (keys key[], increasing) at key x, and the direction
 * of its edge there (tangent, not unit; NULL: not asked); *at is a cursor (the keys asked for
 * increase). */
static void point_at(const cf_ctx *c, const uint32_t *v, const double *key, size_t n, double x,
                     size_t *at, double out[3], double tangent[3])
{
    while (*at + 2 < n && key[*at + 1] <= x)
        (*at)++;
    size_t i = *at;
    double span = key[i + 1] - key[i], w = span > 0 ? (x - key[i]) / span : 0.0;
    w = w < 0 ? 0 : w > 1 ? 1 : w;
    const double *a = c->m->pos + 3 * (size_t)v[i], *b = c->m->pos + 3 * (size_t)v[i + 1];
    for (int k = 0; k < 3; k++) {
        out[k] = a[k] + w * (b[k] - a[k]);
        if (tangent)
            tangent[k] = b[k] - a[k];
    }
}

/* The row's point above curve point a (tangent ta there), toward b on the loop's row: b less
 * its lean along the curve (the row's parameters run a little ahead of or behind the curve's;
 * leaning rows were sheared against each other by their distances: triangles of 27° under
 * the 38.7° the rows make upright, x y z = 0 in the irrational box). */
static void upright(const double a[3], const double ta[3], const double b[3], double out[3])
{
    double d[3], tt = ism_dot3(ta, ta), w;
    for (int k = 0; k < 3; k++)
        d[k] = b[k] - a[k];
    w = tt > 0 ? ism_dot3(d, ta) / tt : 0.0;
    for (int k = 0; k < 3; k++)
        out[k] = b[k] - w * ta[k];
}

/* Zips row a (keys ka, na vertices) to the row below it, b (kb, nb), both keys running from 0
 * to 1 with their first and last vertices on the strip's sides: each step takes the shorter
 * new edge — (a_i, a_i+1, b_j) advancing a, (a_i, b_j+1, b_j) advancing b — in s, or in space
 * (by_length: the loop's row over the top row, which stand apart by the octree's staircase:
 * by s its steps up and down made triangles of 31° under the comfort of the quality pass). */
static bool zip_rows(cf_ctx *c, const uint32_t *a, const double *ka, size_t na,
                     const uint32_t *b, const double *kb, size_t nb, bool by_length)
{
    size_t i = 0, j = 0;
    const double *x = c->m->pos;
    while (i + 1 < na || j + 1 < nb) {
        bool adv_a = j + 1 == nb;
        if (!adv_a && i + 1 < na) {
            double da = by_length ? ism_dist3(x + 3 * (size_t)a[i + 1], x + 3 * (size_t)b[j])
                                  : fabs(ka[i + 1] - kb[j]);
            double db = by_length ? ism_dist3(x + 3 * (size_t)a[i], x + 3 * (size_t)b[j + 1])
                                  : fabs(kb[j + 1] - ka[i]);
            adv_a = da <= db;
        }
        if (adv_a ? !cf_add_triangle(c, a[i], a[i + 1], b[j])
                  : !cf_add_triangle(c, a[i], b[j + 1], b[j]))
            return false;
        adv_a ? i++ : j++;
    }
    return true;
}

/* Keys from 0 to 1 along the stretch, measured as the curve's parameters bx[0 .. nb) run:
 * key[i] = (x[i] − bx[0]) / (bx[nb−1] − bx[0]) within [0, 1], the ends 0 and 1 (the sides).
 * The rows stand upright over the curve, so the row's vertices are keyed by their own feet:
 * keyed by its own range instead (its ends' feet snapped to a junction or not), a row vertex
 * a fifth of the stretch away from its foot was fanned over the rows' vertices under it
 * (x y z = 0, irrational box: 2.8°). */
static void scale_keys(const double *x, size_t n, const double *bx, size_t nb, double *key)
{
    double span = bx[nb - 1] - bx[0];
    for (size_t i = 0; i < n; i++)
        key[i] = fmin(1.0, fmax(0.0, (x[i] - bx[0]) / span));
    key[0] = 0.0;
    key[n - 1] = 1.0;
}

/* The strip's mean width over the curve's vertices (bot, bk, nb, the stretch len long; the
 * loop's row top, tk, nt), held to GRADE_BETA_MIN .. GRADE_BETA_MAX of the width that puts
 * each of K rows as far above the one below as that row's spacing (β = 1): the rows below the
 * top keep their triangles' angles at atan(0.8) = 38.7° and more whatever the strip's width
 * (the top layer takes the rest; the mean alone gave β 1.44 where a strip stood wide on
 * x y z = 0, 34.8°). */
static double held_width(const cf_ctx *c, const uint32_t *bot, const double *bk, size_t nb,
                         double len, const uint32_t *top, const double *tk, size_t nt, int K)
{
    double mean = 0;
    for (size_t j = 0, at_t = 0; j < nb; j++) {
        double pb[3], tb[3], pt[3], up[3];
        size_t at_b = j ? j - 1 : 0;
        point_at(c, bot, bk, nb, bk[j], &at_b, pb, tb);
        point_at(c, top, tk, nt, bk[j], &at_t, pt, NULL);
        upright(pb, tb, pt, up);
        mean += ism_dist3(pb, up) / (double)nb;
    }
    double ideal = len / (double)(nb - 1) * (pow(GRADE_RATIO, K + 1) - 1);
    return fmin(GRADE_BETA_MAX * ideal, fmax(GRADE_BETA_MIN * ideal, mean));
}

/* Row k's vertices between its sides (row[k][0] and row[k][cnt[k] − 1], set): each over every
 * other vertex of the row below, at t (the fraction) of the way up — the lower rows straighter
 * than the loop's row: t (w̄ + t (w − w̄)) above the curve, w the width there, w̄ the strip's
 * held width (the row's steps, the octree's staircase 0.11 to 0.16 from the axis on
 * x y z = 0, carried down whole made every row's gaps vary as much: 33° where the row stood
 * wide). False when out of memory. */
static bool fill_row(cf_ctx *c, double t, double mean, uint32_t *const *row,
                     double *const *rk, const size_t *cnt, int k, int K)
{
    size_t n = cnt[k], at_b = 0, at_t = 0;
    rk[k][0] = 0.0;
    rk[k][n - 1] = 1.0;
    for (size_t j = 1; j + 1 < n; j++) {
        double s = rk[k - 1][2 * j], pb[3], tb[3], pt[3], up[3];
        point_at(c, row[0], rk[0], cnt[0], s, &at_b, pb, tb);
        point_at(c, row[K + 1], rk[K + 1], cnt[K + 1], s, &at_t, pt, NULL);
        upright(pb, tb, pt, up);
        rk[k][j] = s;
        double w = ism_dist3(pb, up), share = w > 0 ? t * (mean + t * (w - mean)) / w : t;
        if ((row[k][j] = row_vertex(c, pb, up, share)) == CF_NONE)
            return false;
    }
    return true;
}

int cf_grade_strip(cf_ctx *c, cf_grade *g, const uint32_t *top, const double *tx, size_t nt,
                   const uint32_t *bot, const double *bx, size_t nb)
{
    if (nt < 2 || nb < 2 || !(tx[nt - 1] > tx[0]) || !(bx[nb - 1] > bx[0]))
        return -1;
    int K = g->rows;
    const uint32_t *left = side(c, g, top[0], bot[0]);
    const uint32_t *right = left ? side(c, g, top[nt - 1], bot[nb - 1]) : NULL;
    if (!right)
        return 0;
    /* the rows' vertex counts: each row half the edges of the one below (an odd one's last
     * edge over three), one at least */
    size_t cnt[CF_GRADE_MAX_ROWS + 2], total = 0;
    for (int k = 0; k <= K + 1; k++) {
        size_t half = k > 0 ? (cnt[k - 1] - 1) / 2 : 0;
        cnt[k] = k == 0 ? nb : k == K + 1 ? nt : (half > 1 ? half : 1) + 1;
        total += cnt[k];
    }
    uint32_t *v = malloc(total * sizeof *v);
    double *key = malloc(total * sizeof *key);
    int ret = 0;
    if (!v || !key)
        goto done;
    uint32_t *row[CF_GRADE_MAX_ROWS + 2];
    double *rk[CF_GRADE_MAX_ROWS + 2];
    size_t off = 0;
    for (int k = 0; k <= K + 1; k++) {
        row[k] = v + off;
        rk[k] = key + off;
        off += cnt[k];
    }
    for (size_t j = 0; j < nb; j++)
        row[0][j] = bot[j];
    for (size_t i = 0; i < nt; i++)
        row[K + 1][i] = top[i];
    scale_keys(bx, nb, bx, nb, rk[0]);
    scale_keys(tx, nt, bx, nb, rk[K + 1]);
    double mean = held_width(c, row[0], rk[0], nb, bx[nb - 1] - bx[0], row[K + 1], rk[K + 1],
                             nt, K);
    for (int k = 1; k <= K && !c->stopped; k++) {
        row[k][0] = left[k];
        row[k][cnt[k] - 1] = right[k];
        if (!fill_row(c, g->t[k], mean, row, rk, cnt, k, K))
            goto done;
    }
    for (int k = K + 1; k >= 1 && !c->stopped; k--) /* stopped: the caller undoes */
        if (!zip_rows(c, row[k], rk[k], cnt[k], row[k - 1], rk[k - 1], cnt[k - 1], k == K + 1))
            goto done;
    ret = 1;
done:
    free(v);
    free(key);
    return ret;
}
