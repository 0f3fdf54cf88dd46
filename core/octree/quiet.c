/* quiet.c — does a box lie in one of the quiet balls (see quiet.h)? The balls' grid
 * (ball_grid.h) is read in the 27 cells around the box's centre. */
#include "core/octree/quiet.h"

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

static bool inside(const double *b, const double lo[3], const double hi[3])
{
    double far = 0;
    for (int a = 0; a < 3; a++) {
        double d = fmax(fabs(lo[a] - b[a]), fabs(hi[a] - b[a]));
        far += d * d;
    }
    return far < b[3] * b[3];
}

bool ism_quiet_holds(const ism_quiet *q, const double lo[3], const double hi[3])
{
    const ism_ball_grid *g = &q->grid;
    if (g->n == 0)
        return false;
    double mid[3];
    for (int a = 0; a < 3; a++) {
        mid[a] = 0.5 * (lo[a] + hi[a]);
        if (hi[a] - lo[a] > 2 * g->cell)
            return false; /* larger than any ball */
    }
    int64_t c0[3];
    ism_ball_grid_cell_of(g, mid, c0);
    for (int d = 0; d < 27; d++) {
        int64_t c[3] = {c0[0] + d % 3 - 1, c0[1] + d / 3 % 3 - 1, c0[2] + d / 9 - 1};
        for (size_t i = ism_ball_grid_first(g, c); ism_ball_grid_in(g, i, c); i++)
            if (inside(q->ball[g->key[i] & UINT32_MAX], lo, hi))
                return true;
    }
    return false;
}

static bool meets(const double *b, const double lo[3], const double hi[3])
{
    double near = 0;
    for (int a = 0; a < 3; a++) {
        double d = b[a] < lo[a] ? lo[a] - b[a] : b[a] > hi[a] ? b[a] - hi[a] : 0;
        near += d * d;
    }
    return near < b[3] * b[3];
}

/* A meeting ball's centre lies within one grid cell (the largest radius) of the box: the
 * cells from lo's to hi's, grown by one. */
bool ism_quiet_meets(const ism_quiet *q, const double lo[3], const double hi[3])
{
    const ism_ball_grid *g = &q->grid;
    if (g->n == 0)
        return false;
    int64_t c0[3], c1[3];
    ism_ball_grid_cell_of(g, lo, c0);
    ism_ball_grid_cell_of(g, hi, c1);
    int64_t c[3];
    for (c[0] = c0[0] - 1; c[0] <= c1[0] + 1; c[0]++)
        for (c[1] = c0[1] - 1; c[1] <= c1[1] + 1; c[1]++)
            for (c[2] = c0[2] - 1; c[2] <= c1[2] + 1; c[2]++)
                for (size_t i = ism_ball_grid_first(g, c); ism_ball_grid_in(g, i, c); i++)
                    if (meets(q->ball[g->key[i] & UINT32_MAX], lo, hi))
                        return true;
    return false;
}
