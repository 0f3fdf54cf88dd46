/* tile_corners.h — a tile's four corners (the face walk's order), as lattice points and as
 * world positions, from one table of which end of u and of v each corner takes, so the two
 * cannot disagree. */
#ifndef ISM_TILE_CORNERS_H
#define ISM_TILE_CORNERS_H

#include "core/octree/grid.h"
#include "core/octree/octree.h"

/* Corner k takes u1 when ISM_TILE_CORNER_U[k] (else u0) and v1 when ISM_TILE_CORNER_V[k]:
 * counter-clockwise in (u, v) from (u0, v0): (u0, v0), (u1, v0), (u1, v1), (u0, v1). */
static const int ISM_TILE_CORNER_U[4] = {0, 1, 1, 0};
static const int ISM_TILE_CORNER_V[4] = {0, 0, 1, 1};

/* Tile t's four corners as lattice points. */
static inline void ism_tile_corners(const ism_tile *t, int32_t q[4][3])
{
    int u = ism_axis_next(t->axis), v = ism_axis_prev(t->axis);
    int32_t cu[2] = {t->u0, t->u1}, cv[2] = {t->v0, t->v1};
    for (int k = 0; k < 4; k++) {
        q[k][t->axis] = t->plane;
        q[k][u] = cu[ISM_TILE_CORNER_U[k]];
        q[k][v] = cv[ISM_TILE_CORNER_V[k]];
    }
}

/* ... and their world positions, as ism_grid_point gives them (the same ism_grid_coord of
 * the same integers: the same bits): the tile's five coordinates (its plane, u0, u1, v0, v1)
 * each found once, not twelve times. */
static inline void ism_tile_corner_points(const ism_grid *g, const ism_tile *t, double p[4][3])
{
    int u = ism_axis_next(t->axis), v = ism_axis_prev(t->axis);
    double w = ism_grid_coord(g, t->axis, t->plane);
    double pu[2] = {ism_grid_coord(g, u, t->u0), ism_grid_coord(g, u, t->u1)};
    double pv[2] = {ism_grid_coord(g, v, t->v0), ism_grid_coord(g, v, t->v1)};
    for (int k = 0; k < 4; k++) {
        p[k][t->axis] = w;
        p[k][u] = pu[ISM_TILE_CORNER_U[k]];
        p[k][v] = pv[ISM_TILE_CORNER_V[k]];
    }
}

#endif
