/* sp_collapse.h — the simplification's edge collapses (sp_collapse.c): one round over the
 * mesh's edges with an active end, shortest first, a merged vertex in no other collapse that
 * round. */
#ifndef ISM_SP_COLLAPSE_H
#define ISM_SP_COLLAPSE_H

#include "core/remesh/rm_pass.h"

/* What the rounds remember of refused collapses: an edge refused since nothing changed
 * around it is not tried again. "Changed" is a merge or a flip: a new fan at a vertex of
 * the edge's ends' fans (the triangles the verdict and a trial read), its stamp then later
 * than the refusal's. Vertices moved by relaxation or a trial's ring do not count: a
 * refused edge whose fans were only evened out is refused again nearly always (callgrind
 * bench_error mesh S E 10: of the sphere's 7.93e-4 2,998 such retries, 20 merged).
 * Only what is tried changes: every merge taken is still measured. Sphere 7.93e-4 /
 * torus 2.4e-3, simplification 781M -> 720M / 725M -> 704M instructions, 4,098 -> 4,148 /
 * 2,294 -> 2,302 triangles. */
typedef struct sp_history {
    uint32_t *changed; /* per vertex: the clock when its fan last changed */
    uint32_t *refused; /* per triangle corner k (3 t + k), for the edge from corner k to
                          k + 1: the clock when its collapse was last refused, 0 never */
    uint8_t *flipped;  /* per vertex: a corner of a flip (rm_pass.flipped) since the last
                          sp_history_flips */
    uint32_t clock;
} sp_history;

/* Room for p's vertices and triangles; false when out of memory. sp_history_free either way. */
bool sp_history_open(sp_history *h, const rm_pass *p);
void sp_history_free(sp_history *h);
/* Stamps the corners of the flips made since the last call as changed. */
void sp_history_flips(sp_history *h, size_t nverts);

/* Collapses the edges whose merge keeps the mesh within max_error (every new centroid and
 * edge midpoint measured, rm_bound.h), its topology (the link condition), its features
 * (locked vertices stay where they are, locked edges are never collapsed), its orientation
 * (no new triangle turns against its old self or the surface's normal at its corners) and
 * its shape (no new angle below the fan's smallest before, or below ISM_SP_MIN_DEG). Only
 * edges with an active end are tried; then the corners of the new triangles are the active
 * ones. Edges refused before, with no change around them since (h), are not tried. Polls
 * cancel every few hundred edges.
 * Returns the collapses made; *ok false when out of memory. */
size_t sp_collapse_round(rm_pass *p, sp_history *h, const volatile int *cancel, bool *ok);

#endif
