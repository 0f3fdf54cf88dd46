/* conform_stats.h — what the conformance pass (conform.h) counts, and how often it polls
 * its deadline: data only, shared by the pass's driver and its surgeries. */
#ifndef ISM_CONFORM_STATS_H
#define ISM_CONFORM_STATS_H

#include <stddef.h>

typedef struct ism_conform_stats {
    size_t points_conformed;   /* points made one vertex with at least one cone of faces */
    size_t points_failed;      /* sheet-carrying points with no hole loop around them (no
                                  mesh there), or out of the box: cones = 0 */
    size_t points_short_cones; /* nodes with fewer than the 2 cones their Hessian promises
                                  (a nappe the polygoniser lost beyond the ball) */
    size_t points_skipped;     /* isolated points (no sheet), pinch and triple points (made
                                  vertices as ends of their curves) */
    size_t curves_conformed;   /* double curves zipped into the mesh */
    size_t curves_kept;        /* ... of them found a chain of edges in the polygoniser's
                                  mesh already (conform_kept.c): no surgery */
    size_t curves_failed;      /* double curves with no hole loop along them */
    size_t curves_skipped;     /* whiskers (no sheet; they stay in the locus) */
    size_t loops_fallback;     /* hole loops that could not be zipped to their curve and were
                                  closed by a fan to their projected centroid instead (no
                                  crack, but not conforming there) */
    size_t cuts_widened;       /* cuts made again wider because another sheet came near
                                  their rim (the polygoniser's confusion reached further) */
    size_t triangles_removed, triangles_added;
    size_t refill_turned;      /* the pass's triangles, and the polygoniser's beside pinch
                                  points, facing against ∇f before untangling
                                  (conform_refine.c) */
    size_t refill_untangled;   /* moves of vertices that turned triangles back */
    size_t refill_splits;      /* edges of the pass's triangles halved because a centroid
                                  or midpoint was farther than E (max_error; without one a
                                  quarter of the finest cell, conform_refine.c) */
    size_t refill_over_error;  /* ... triangles left farther than E (the edge to halve would
                                  be shorter than the finest cell of depth.max — half of it
                                  without max_error — or its midpoint finds no foot, or a
                                  half would turn over) */
    size_t refill_work;        /* the units of `work` the untangling took (after the
                                  surgeries) */
    size_t vertices_added, vertices_removed;
    size_t work;               /* units of work done: candidate triangles tested, rim edges
                                  and rim vertices checked, vertices projected, triangles
                                  added (what the pass polls its deadline by) */
    size_t polls;              /* deadline and cancel checks made (one per
                                  ISM_CONFORM_POLL_WORK units at most) */
    size_t items_stopped;      /* surgeries stopped in the middle (deadline, cancel, work
                                  budget) and undone: their place left as the polygoniser
                                  made it */
    size_t grid_passes;        /* passes over the polygoniser's triangles that filed them in
                                  the pass's triangle grid (conform_grid.c's cover passes) */
    double time_ms;
} ism_conform_stats;

/* The pass checks its deadline and cancel flag after at most this many units of work (0.1 to
 * a few microseconds each: at most a few milliseconds between checks; a check is a clock read),
 * inside every surgery, however large: one double curve can hold most of a mesh. */
#define ISM_CONFORM_POLL_WORK 1024

#endif
