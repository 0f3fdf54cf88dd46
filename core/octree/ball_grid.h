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

/* Does hit(ball index, arg) hold for a ball filed in one of the cells c0..c1 (inclusive on
 * every axis)? Stops at the first that does. The cells are read a column at a time: a run
 * of cells along z has consecutive keys, so one binary search finds the run's entries (a
 * box grown by 4 cells an axis reads 9² columns, not 9³ cells). */
bool ism_ball_grid_any(const ism_ball_grid *g, const int64_t c0[3], const int64_t c1[3],
                       bool (*hit)(uint32_t ball, const void *arg), const void *arg);

#endif
