/* grid.c — the lattice under the octree: maps integer lattice points to world coordinates. */
#include "core/octree/grid.h"

#include <math.h>

void ism_grid_init(ism_grid *g, const double box[6], int depth)
{
    g->depth = depth;
    double n = ldexp(1.0, depth);
    for (int k = 0; k < 3; k++) {
        g->lo[k] = box[k];
        g->step[k] = (box[3 + k] - box[k]) / n; /* division by a power of two: exact */
    }
}

double ism_grid_cell_size(const ism_grid *g, int level)
{
    double s = g->step[0];
    for (int k = 1; k < 3; k++)
        if (g->step[k] < s)
            s = g->step[k];
    return s * (double)ism_grid_cell_steps(g, level);
}
