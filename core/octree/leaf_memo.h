/* leaf_memo.h — what each leaf of a max_error round emitted, kept for the next round. A
 * leaf's polygons depend only on what lies in its closed box: its corners and edges, the
 * tiles the leaves across its faces make of them, and the break points other leaves put on
 * its edges and tiles (breaks.h). The next round's tree is this one with some leaves split
 * (octree_build.h, previous), so a leaf of both trees whose closed box shares no edge
 * segment or face with a leaf split since emits the same triangles, bit for bit: they are
 * copied instead of computed. (A leaf touching a split one at a corner alone keeps its
 * output: that corner is the only point of the split leaf's box in its own, a lattice point
 * before and after.) */
#ifndef ISM_LEAF_MEMO_H
#define ISM_LEAF_MEMO_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/octree/cell_stats.h"
#include "core/octree/cell_types.h"
#include "core/octree/octree.h"

/* Where one leaf's output lies in its chunk's output, what it measured and counted. */
typedef struct ism_leaf_rec {
    size_t chunk, v0, t0, s0;  /* its first vertex, triangle, segment in out[chunk] */
    size_t nv, nt, ns;
    float error;               /* ism_emitted_error of its triangles */
    ism_cell_stats stats;      /* what polygonising it added to the counters */
} ism_leaf_rec;

typedef struct ism_leaf_memo {
    ism_cell_out *out;         /* the round's chunk outputs (owned) */
    size_t nchunks;
    ism_leaf_rec *rec;         /* one per leaf, leaves in node order (owned) */
    size_t nleaves;
} ism_leaf_memo;

/* For each leaf of `now` (leaves in node order), the index of the same leaf among
 * `before`'s leaves when its output may be copied, else -1 (a leaf new in `now`, or one
 * whose closed box shares an edge segment or a face with a leaf of `before` that `now`
 * splits: ism_node_lboxes_share_segment). `now` must be `before` with leaves split; reuse
 * holds one entry per leaf of `now`. False when out of memory. */
bool ism_leaf_memo_match(const ism_octree *before, const ism_octree *now, int32_t *reuse);

/* Room in out for the outputs of leaves reuse[0..n) (as ism_leaf_memo_match gives them),
 * taken at once: the copied ones' (reuse[i] >= 0) and, for each leaf polygonised afresh,
 * the most a copied one emitted. That overestimates: Barth's sextic at E 0.0259 (84 chunks
 * over its later rounds) ends with room for 2.24× the vertices and 2.28× the triangles its
 * chunks hold; the copied leaves' mean instead gives 1.71× and 1.42× but costs 5.3M instructions
 * more (2,247.0M against 2,241.8M, callgrind --toggle-collect=ism_mesh_surface, bench_error
 * mesh barth-sextic 0.0259 10), the fresh leaves then growing out. The room stays alive through
 * the next round (the arrays become its memo). A later round copies most of a chunk's leaves,
 * and growing out leaf by leaf reallocated it about log2 of its size times (Barth's sextic
 * at E 0.0259: 29M of its 2,358M instructions moving the arrays over 5 later rounds,
 * callgrind counting each byte `rep movsb` moves). False when out of memory. */
bool ism_leaf_memo_reserve(const ism_leaf_memo *m, const int32_t *reuse, size_t n,
                           ism_cell_out *out);

/* Appends leaf `leaf`'s recorded output to out (vertex indices moved to out's), adds its
 * counters to st, and returns the counters added in *added and its measured error in
 * *error. False when out of memory. */
bool ism_leaf_memo_copy(const ism_leaf_memo *m, size_t leaf, ism_cell_out *out,
                        ism_cell_stats *st, ism_cell_stats *added, float *error);

void ism_leaf_memo_free(ism_leaf_memo *m);

#endif
