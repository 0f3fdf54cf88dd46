/* node_balls.h — the balls around certified nodes (cone apices) where the octree splits
 * nodes until they are fine enough to see both nappes (ism_poly_options.node_balls): at a
 * coarse depth a nappe closing into a small piece between nodes crosses no edge of the
 * depth's cells and is lost, and the node is then joined with one cone. The same balls
 * along certified double curves split the nodes down to the curve's own cell
 * (core/singular/curve_cell.h). */
#ifndef ISM_NODE_BALLS_H
#define ISM_NODE_BALLS_H

#include <stdbool.h>
#include <stddef.h>

/* A ball: centre x, y, z, radius, and the size a node meeting it is split down to. */
enum { ISM_NODE_BALL_X, ISM_NODE_BALL_Y, ISM_NODE_BALL_Z, ISM_NODE_BALL_R, ISM_NODE_BALL_CELL,
       ISM_NODE_BALL_FIELDS };

/* Does the box lo..hi meet one of the n balls whose cell is smaller than the box's longest
 * side (the node must then be split)? Linear in n: callers keep n small (see
 * ISM_NODE_BALLS_MAX). */
bool ism_node_balls_split(const double (*ball)[ISM_NODE_BALL_FIELDS], size_t n,
                          const double lo[3], const double hi[3]);

/* Balls a caller passes at most (the test above runs on every node the octree decides). */
#define ISM_NODE_BALLS_MAX 256

#endif
