/* quiet.c — does a box lie in one of the quiet balls (see quiet.h)? The balls' grid
 * (ball_grid.h) is read in the cells that can hold the centre of a ball holding the box. */
#include "core/octree/quiet.h"
#include "core/util/vec3.h"

#include <math.h>

bool ism_quiet_init(ism_quiet *q, const double (*ball)[4], size_t n)
{
    q->ball = ball;
    return ism_ball_grid_init(&q->grid, n ? ball[0] : NULL, 4, 3, n);
}

void ism_quiet_free(ism_quiet *q)
{
    ism_ball_grid_free(&q->grid);
}

/* A query's box and reach, for the grid's visit (ism_ball_grid_any). */
typedef struct query {
    const ism_quiet *q;
    const double *lo, *hi;
    double reach;
} query;

static bool inside(const double *b, const double lo[3], const double hi[3])
{
    double far = 0;
    for (int a = 0; a < 3; a++) {
        double d = fmax(fabs(lo[a] - b[a]), fabs(hi[a] - b[a]));
        far += d * d;
    }
    return far < b[3] * b[3];
}

static bool holds_box(uint32_t ball, const void *arg)
{
    const query *k = arg;
    return inside(k->q->ball[ball], k->lo, k->hi);
}

/* A ball holding the box holds its farthest corner: per axis |mid - centre| + half the side
 * is below the radius, itself at most the grid's cell. So the box is held by none when its
 * half-diagonal reaches the cell, and else the centres lie within cell - half the side of mid
 * on each axis (widened by 1e-9 cell against rounding): the grid cells over that range (2 an
 * axis mostly, 3 at most) are read, not the 27 round mid's. Coordinate planes at the default
 * bound: 4,400 instructions a call before. */
bool ism_quiet_holds(const ism_quiet *q, const double lo[3], const double hi[3])
{
    const ism_ball_grid *g = &q->grid;
    if (g->n == 0)
        return false;
    double a0[3], a1[3], half2 = 0;
    for (int a = 0; a < 3; a++) {
        double mid = 0.5 * (lo[a] + hi[a]), half = 0.5 * (hi[a] - lo[a]);
        half2 += half * half;
        double reach = g->cell - half + 1e-9 * g->cell; /* + rounding's share */
        a0[a] = mid - reach;
        a1[a] = mid + reach;
    }
    if (!(half2 < g->cell * g->cell))
        return false; /* larger than any ball */
    int64_t c0[3], c1[3];
    ism_ball_grid_cell_of(g, a0, c0);
    ism_ball_grid_cell_of(g, a1, c1);
    return ism_ball_grid_any(g, c0, c1, holds_box, &(query){q, lo, hi, 0});
}

/* Does the box come within max(radius, reach) of ball b's centre? */
static bool near(const double *b, const double lo[3], const double hi[3], double reach)
{
    double r = b[3] > reach ? b[3] : reach;
    return ism_sqdist_box3(b, lo, hi) < r * r;
}

static bool near_box(uint32_t ball, const void *arg)
{
    const query *k = arg;
    return near(k->q->ball[ball], k->lo, k->hi, k->reach);
}

/* A ball within reach has its centre within one grid cell (the largest radius) plus reach of
 * the box: the cells from lo's to hi's, grown by that many — or every ball, when they are
 * fewer than those cells (a reach of 5 cells round balls of 2 spans 9³ grid cells: read cell
 * by cell, the double cone's one ball made that +2.6% of the run). The grid is read a column
 * at a time (ism_ball_grid_any, 9² binary searches there): Steiner's 636 reach queries
 * (measure_unflat) and 43,364 reach-0 ones (octree_build.c unflat) cost 396M instructions
 * read cell by cell. */
bool ism_quiet_near(const ism_quiet *q, const double lo[3], const double hi[3], double reach)
{
    const ism_ball_grid *g = &q->grid;
    if (g->n == 0)
        return false;
    int64_t c0[3], c1[3], k = 1 + (int64_t)ceil(reach / g->cell);
    ism_ball_grid_cell_of(g, lo, c0);
    ism_ball_grid_cell_of(g, hi, c1);
    double cells = 1;
    for (int a = 0; a < 3; a++)
        cells *= (double)(c1[a] - c0[a] + 1 + 2 * k);
    if ((double)g->n <= cells) {
        for (size_t i = 0; i < g->n; i++)
            if (near(q->ball[g->key[i] & UINT32_MAX], lo, hi, reach))
                return true;
        return false;
    }
    for (int a = 0; a < 3; a++) {
        c0[a] -= k;
        c1[a] += k;
    }
    return ism_ball_grid_any(g, c0, c1, near_box, &(query){q, lo, hi, reach});
}
