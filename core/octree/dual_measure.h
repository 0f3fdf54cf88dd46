/* dual_measure.h — the dual mesher's triangles and their measure (dual_tree.h's state):
 * each round's quads made triangles, every triangle's centroid and edge midpoints measured
 * against E, and the leaves round the misses marked to split (dnode.split). */
#ifndef ISM_DUAL_MEASURE_H
#define ISM_DUAL_MEASURE_H

#include <stddef.h>
#include <stdint.h>
#include "core/octree/dual_tree.h"
#include "core/octree/edge_keys.h"

/* Vertices a and b in one key (their edge key + 1: never 0, as the memos want), the same
 * either way round. */
static inline uint64_t pair_key(uint32_t a, uint32_t b)
{
    return ism_edge_key(a, b) + 1;
}

/* The midpoint of the pair key stands for into m. */
static inline void pair_mid(const dual *d, uint64_t key, double m[3])
{
    uint32_t a = (uint32_t)((key - 1) >> 32), b = (uint32_t)(key - 1);
#pragma GCC unroll 3
    for (int k = 0; k < 3; k++)
        m[k] = 0.5 * (d->pos[3 * a + k] + d->pos[3 * b + k]);
}

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

/* The miss masks of triangles list[0..n) (list NULL: triangles 0..n) into miss[0..n): a
 * bit per corner, the ends of each edge whose midpoint lies beyond E and all three when the
 * centroid misses (ism_dual_centroid_within_at); 0 within E. Triangles that met E in an
 * earlier round (d->passed) read 0 unmeasured; the rest are measured on the pool and
 * remembered when they pass. Out of memory: d->nomem. */
void ism_dual_measure_triangles(dual *d, const uint32_t *list, size_t n, uint8_t *miss);

/* The distance to f = 0 of the midpoint of vertices a and b (the memo d->mid, else measured
 * on thread 0). */
double ism_dual_mid_dist(dual *d, uint32_t a, uint32_t b);

/* The n <= MEASURE_LANES points m[k] (each near f = 0, within size[k] of it) moved onto
 * f = 0 by Newton and then as a leaf's vertex is (place_vertex: the straddle move) into
 * out[k] (m is overwritten); NaN there when Newton cannot finish. Newton's gradients in one
 * batch a step (ism_dual_newton_lanes), the straddle move's jets in one Hessian batch (as
 * dual.c's place_plain's) for the lanes Newton finished: bit for bit ism_dual_newton_onto
 * then ism_straddle_balanced_point, one point at a time (test_dual_lanes). A pure function
 * of m, like the vertices: fans' centres (fan_task) and cut sides' vertices (side_task). */
void ism_dual_vertices_onto(const dual *d, worker *w, double (*m)[3], const double *size,
                            size_t n, double (*out)[3]);

/* Marks the leaves of the round's triangles that miss E (miss: ism_dual_measure_triangles'
 * masks of all of them); returns how many leaves can still split and counts the misses at
 * max_depth into *missed. A fan's centre (ism_dual_emit_quads) belongs to no leaf: a fan's
 * triangle whose leaves are at max_depth splits the fan's other leaves (mark_fan_leaves). */
size_t ism_dual_mark_misses(dual *d, const uint8_t *miss, uint64_t *missed);

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
