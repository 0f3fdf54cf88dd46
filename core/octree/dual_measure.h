/* dual_measure.h — the dual mesher's triangles and their measure (dual_tree.h's state):
 * each round's quads made triangles, every triangle's centroid and edge midpoints measured
 * against E, and the leaves round the misses marked to split (dnode.split). */
#ifndef ISM_DUAL_MEASURE_H
#define ISM_DUAL_MEASURE_H

#include <stddef.h>
#include <stdint.h>
#include "core/octree/dual_tree.h"

/* The round's quads as triangles. Each is cut across the diagonal whose midpoint lies nearer
 * f = 0 — where the surface is a saddle (the torus's inner half) the two diagonals sag to
 * opposite sides and the shorter one is as often the worse: choosing by distance took the
 * torus's triangles under 1e-2 / 3e-3 / 1e-3 from 3,616 / 7,120 / 23,744 to 3,280 / 5,968
 * / 20,464 for two distance samples per quad —, and when those two triangles miss E, into
 * four round a centre on f = 0 (fan_task) instead: their longest edges are the quad's sides,
 * which sag half as far as its diagonal (κ s² / 8 against κ s² / 4 for a square of side s),
 * so a quad that the diagonal would have split its leaves for (four times the quads, twice
 * the triangles' count each) may meet E as it is. Whether a fan meets E is measured like
 * any triangle (ism_dual_mark_misses); a quad once cut as a fan keeps its centre (d->fans). */
void ism_dual_emit_quads(dual *d);

/* Marks the leaves of triangles that miss E (centroid and edge midpoints within E of f = 0,
 * facing along ∇f: measure_triangles); returns how many leaves can still split and counts
 * the misses at max_depth into *missed. A fan's centre (ism_dual_emit_quads) belongs to no leaf: a
 * fan's triangle whose leaves are at max_depth splits the fan's other leaves
 * (mark_fan_leaves). Where every miss is a side between two leaves' vertices just past E
 * (within SIDE_SPLIT_MAX E, each missed by its two triangles and nothing else missed: split_sides), the
 * sides are cut instead, each triangle in two at a vertex on the side's midpoint's foot,
 * and when all the halves meet E they stand in the mesh and nothing is marked (0): a
 * sphere-like surface's last round was often a whole level of leaves split for a few chords
 * a hair too long. Not with a crease, the grown box or isolated points. */
size_t ism_dual_mark_misses(dual *d, uint64_t *missed);

/* In the grown box: the triangles across the request's box's planes clipped as the final
 * mesh will be (dual_box.h), and the leaves of each with a piece beyond E marked to split;
 * returns how many can still split and counts the misses at max_depth into *missed. A cut
 * point that will not settle declines (box_cut). */
size_t ism_dual_mark_cut_misses(dual *d, uint64_t *missed);

/* With a crease (dual_crease.h): the leaves at the ends of every mesh edge more than two
 * triangles share, and of every vertex joining two fans, marked to split (two crease pieces
 * in one small leaf, judged by the measurement alone, join two sheets there: Barth's
 * clipped sextic at 1e-2 had 4 such edges, then one such vertex); at depth.max the crease is
 * not followed (min_max). Returns the leaves newly marked. */
size_t ism_dual_mark_not_manifold(dual *d);

#endif
