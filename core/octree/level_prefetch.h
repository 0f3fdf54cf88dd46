/* level_prefetch.h — the pure values the octree build's flatness tests read through their
 * memos (cell_cache.h: f and ∇f at node corners, single roots on node edges), computed ahead
 * for many nodes of one level at once in wide batches: the corners' points in
 * ism_sample_grad_batch calls of up to PREFETCH_POINTS points, the edges' roots by regula
 * falsi in lanes (ism_regula_falsi_lanes). A depth-first build tests one node at a time, so
 * its batches were 6–10 points wide, where the batched evaluators cost most per point
 * (evb26: the gradient batch 345 / 244 instructions a point at 6 / 10 points, 177–209 at
 * 16–32). Every value is the one the test would compute (batch = scalar bit for bit), so a
 * prefetch changes no decision: only which memo entries are evaluated where (the build's
 * evaluation counts). */
#ifndef ISM_LEVEL_PREFETCH_H
#define ISM_LEVEL_PREFETCH_H

#include <stddef.h>
#include "core/octree/cell_cache.h"
#include "core/octree/corners.h"
#include "core/octree/octree.h"

/* Nodes a call takes at most (the level build's chunk, level_build.c LEVEL_CHUNK). */
#define ISM_PREFETCH_MAX_NODES 128

/* For nodes nd[0..n): f and ∇f at their 8 corners into the corner memo (2^bits entries), as
 * octree_build.c's node_corners would find them — a point the memo holds is skipped, the
 * others evaluated together (a later point mapped to a slot taken in the same batch takes
 * it over) — and into k[i] as node_corners fills them (memo: k's), have[i] false where a
 * slot was taken over before it was read; then the single roots cell_error.c's edge_roots
 * searches on their edges (corners of opposite sign, neither 0, of nodes whose f is finite
 * at all 8) into the root memo and its log, as a search there appends them, skipping edges
 * the memo holds: the searches in lanes (ism_regula_falsi_lanes), node i's on tape[i] (tape
 * NULL, or tape[i] NULL: s->tape; a tape whose f is s->tape's inside the node, as a shortened
 * one is: a set of lanes runs one tape), the corners on s->tape. n is at most
 * ISM_PREFETCH_MAX_NODES. */
void ism_prefetch_nodes(const ism_node_memo *memo, ism_point_entry *table, int bits,
                        const ism_grid *g, const ism_node *const *nd,
                        const ism_tape *const *tape, size_t n, ism_sampler *s, ism_corners *k,
                        bool *have);

#endif
