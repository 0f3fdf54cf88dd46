/* node_balls.h — the balls around certified nodes (cone apices) where the octree splits
 * nodes until they are fine enough to see both nappes (ism_poly_options.node_balls): at a
 * coarse depth a nappe closing into a small piece between nodes crosses no edge of the
 * depth's cells and is lost, and the node is then joined with one cone. The same balls
 * along certified double curves split the nodes down to the curve's own cell
 * (core/singular/curve_cell.h). Indexed in a grid (ball_grid.h): a node's test reads the
 * cells round it, not every ball. */
#ifndef ISM_NODE_BALLS_H
#define ISM_NODE_BALLS_H

#include <stdbool.h>
#include <stddef.h>
#include "core/octree/ball_grid.h"

/* A ball: centre x, y, z, radius, and the size a node meeting it is split down to. */
enum { ISM_NODE_BALL_X, ISM_NODE_BALL_Y, ISM_NODE_BALL_Z, ISM_NODE_BALL_R, ISM_NODE_BALL_CELL,
       ISM_NODE_BALL_FIELDS };

typedef struct ism_node_balls {
    const double (*ball)[ISM_NODE_BALL_FIELDS]; /* not owned */
    size_t n;
    ism_ball_grid grid;
} ism_node_balls;

/* Indexes n balls (kept by the caller while x is used). False when memory ran out. */
bool ism_node_balls_init(ism_node_balls *x, const double (*ball)[ISM_NODE_BALL_FIELDS],
                         size_t n);
void ism_node_balls_free(ism_node_balls *x);

/* Does the box lo..hi meet one of the balls whose cell is smaller than the box's longest
 * side (the node must then be split)? Reads the grid cells within a radius of the box, or
 * every ball when those cells are more than the balls or than NODE_BALLS_SCAN_CELLS (a box
 * much larger than the balls: the octree's few top nodes). */
bool ism_node_balls_split(const ism_node_balls *x, const double lo[3], const double hi[3]);

/* Balls a caller passes at most: 5 doubles each, the test above bounded by the cells it
 * reads. 108 double curves of 9 planes crossing (sin πx sin πy sin πz in ±1.2, depth 3) ask
 * for 500; 256, the bound when every node scanned every ball, left 52 of them unsplit, and
 * their group of curves (joined at 27 triple points) unconformed. */
#define ISM_NODE_BALLS_MAX 8192

#endif
