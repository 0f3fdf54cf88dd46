/* node_balls.c — does a node meet a ball around a certified node or along a double curve
 * finer than itself (see node_balls.h)? */
#include "core/octree/node_balls.h"
#include "core/util/vec3.h"

#include <math.h>

/* Grid cells a query reads at most before it scans every ball instead: 5³, a box up to two
 * cells (the largest radius) wide grown by a cell on each side. Larger boxes are among the
 * octree's top nodes, few and visited once. */
#define NODE_BALLS_SCAN_CELLS 125

bool ism_node_balls_init(ism_node_balls *x, const double (*ball)[ISM_NODE_BALL_FIELDS],
                         size_t n)
{
    x->ball = ball;
    x->n = n;
    return ism_ball_grid_init(&x->grid, n ? ball[0] : NULL, ISM_NODE_BALL_FIELDS,
                              ISM_NODE_BALL_R, n);
}

void ism_node_balls_free(ism_node_balls *x)
{
    ism_ball_grid_free(&x->grid);
}

/* Does ball b (asking for cells below `side`) meet the closed box lo..hi? */
static bool meets(const double *b, double side, const double lo[3], const double hi[3])
{
    if (!(b[ISM_NODE_BALL_CELL] < side))
        return false;
    return ism_sqdist_box3(b, lo, hi) <= b[ISM_NODE_BALL_R] * b[ISM_NODE_BALL_R];
}

/* A query's box and size, for the grid's visit (ism_ball_grid_any). */
typedef struct query {
    const ism_node_balls *x;
    const double *lo, *hi;
    double side;
} query;

static bool meets_box(uint32_t ball, const void *arg)
{
    const query *k = arg;
    return meets(k->x->ball[ball], k->side, k->lo, k->hi);
}

bool ism_node_balls_split(const ism_node_balls *x, const double lo[3], const double hi[3])
{
    const ism_ball_grid *g = &x->grid;
    double side = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    int64_t c0[3], c1[3];
    double cells = 1;
    if (g->n) { /* the centres of the balls meeting the box lie within a cell of it */
        double glo[3], ghi[3];
        for (int a = 0; a < 3; a++) {
            glo[a] = lo[a] - g->cell;
            ghi[a] = hi[a] + g->cell;
        }
        ism_ball_grid_cell_of(g, glo, c0);
        ism_ball_grid_cell_of(g, ghi, c1);
        for (int a = 0; a < 3; a++)
            cells *= (double)(c1[a] - c0[a] + 1);
    }
    if (!g->n || !(cells <= NODE_BALLS_SCAN_CELLS) || cells >= (double)x->n) {
        for (size_t i = 0; i < x->n; i++)
            if (meets(x->ball[i], side, lo, hi))
                return true;
        return false;
    }
    return ism_ball_grid_any(g, c0, c1, meets_box, &(query){x, lo, hi, side});
}
