/* ball_grid.h — balls filed in a uniform grid by their centres, cells as large as the largest
 * radius: a ball meeting a box has its centre in the cells the box covers grown by one cell.
 * The index under quiet.h and node_balls.h. */
#ifndef ISM_BALL_GRID_H
#define ISM_BALL_GRID_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct ism_ball_grid {
    double origin[3], cell;  /* cells of side `cell` from origin (0: no grid) */
    uint64_t *key;           /* per entry: (cell key << 32) | ball index, sorted */
    size_t n;
} ism_ball_grid;

/* Files the n balls at ball[i * stride] (x, y, z, and the radius at field `radius`). An
 * empty grid (n 0) when there are none or their radii are not finite and positive. False
 * when memory ran out. */
bool ism_ball_grid_init(ism_ball_grid *g, const double *ball, size_t stride, size_t radius,
                        size_t n);
void ism_ball_grid_free(ism_ball_grid *g);

/* The cell holding point p. */
void ism_ball_grid_cell_of(const ism_ball_grid *g, const double p[3], int64_t c[3]);

/* The first entry of cell c (index into key; entries of c follow while ism_ball_grid_in
 * holds). */
size_t ism_ball_grid_first(const ism_ball_grid *g, const int64_t c[3]);

/* Is entry i (< n) one of cell c's? Its ball is key[i] & UINT32_MAX. */
bool ism_ball_grid_in(const ism_ball_grid *g, size_t i, const int64_t c[3]);

#endif
