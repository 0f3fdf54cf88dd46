/* sp_trial.h — a collapse tried for real (sp_trial.c). A merge that measures a little beyond
 * the bound on its own may fit once its ring of neighbours has moved to spread the larger
 * triangles around it: the greedy collapses otherwise stop where every single merge would
 * overshoot, on the sphere at about 1.5 times the fewest triangles the bound allows. The
 * caller snapshots what the merge and the ring's moves can change, applies the merge,
 * settles the ring, and restores the snapshot when the ring does not come within the bound. */
#ifndef ISM_SP_TRIAL_H
#define ISM_SP_TRIAL_H

#include "core/remesh/rm_merge.h"
#include "core/remesh/rm_pass.h"

/* At most this many vertices in a merge's ring (v, w and their neighbours) and triangles in
 * v's and w's fans: a larger merge is not tried. */
#define SP_TRIAL_MAX_RING 64
#define SP_TRIAL_MAX_TRIS (2 * ISM_RM_MERGE_MAX_DEGREE)
/* Slots whose contents the merge changes: v's, w's, c's and d's. */
#define SP_TRIAL_SLOTS 4

typedef struct sp_slot {
    uint32_t v, start, room, count;
    uint32_t t[ISM_RM_MERGE_MAX_DEGREE + ISM_RM_SLACK + 2];
} sp_slot;

typedef struct sp_snapshot {
    uint32_t ring[SP_TRIAL_MAX_RING];
    double pos[SP_TRIAL_MAX_RING][3], normal[SP_TRIAL_MAX_RING][3];
    float mesh_normal[SP_TRIAL_MAX_RING][3];
    uint8_t active[SP_TRIAL_MAX_RING];
    int nring;
    uint32_t tri[SP_TRIAL_MAX_TRIS], corners[SP_TRIAL_MAX_TRIS][3];
    int ntri;
    sp_slot slot[SP_TRIAL_SLOTS];
    uint32_t v;
    uint8_t v_flags[4];               /* gone, locked, slide, active */
    size_t collapses, moves;
} sp_snapshot;

/* Records what merging g->v into g->w and moving their ring can change. False when the merge
 * is too large to record (then it is not tried). */
bool sp_snapshot_take(const rm_pass *p, const rm_merge *g, sp_snapshot *s);

/* Puts back everything recorded: positions, normals and active marks of the ring, the
 * triangles' corners and dead marks, the four slots, v's marks and the counters (a refused
 * trial leaves nothing for the next round to try again). */
void sp_snapshot_restore(rm_pass *p, const sp_snapshot *s);

/* After the merge: each free vertex of the ring that is a corner of a triangle of w's fan
 * whose centroid, or the end of an edge at w whose midpoint, lies beyond max_error relaxes
 * toward its fan's centroid and takes its balancing offset, under the pass's usual tests;
 * then w takes its offset. True when then every centroid, edge midpoint and vertex of the
 * triangles around a moved vertex and around w lies within max_error (the triangles of no
 * moved vertex are the ones before the trial). Moving only those corners, not all of w's
 * neighbours: callgrind bench_error mesh S E 10, trial evaluations sphere 7.93e-4 545K ->
 * 328K, torus 2.4e-3 439K -> 198K; triangles 4,068 -> 4,072 and 2,256 -> 2,310. */
bool sp_ring_settle(rm_pass *p, const sp_snapshot *s, uint32_t w);

#endif
