/* straddle.h — under an error bound, a mesh vertex on f = 0 where the surface bends the same
 * way in every direction (both principal curvatures of one sign: sphere-like, not a saddle)
 * is moved toward the surface's convex side by a fixed share of the bound. The chords of
 * such a surface all lie on its concave side, so the mesh then straddles the surface: its
 * vertices err by the shift and its centroids and edge midpoints by their sag minus it, and
 * polygons whose sag reaches (1 + share) × E still meet E — cells about √1.9 times larger.
 *
 * The move is a pure function of the point (f, ∇f and the Hessian there, and the box), so
 * every node that shares a vertex predicts, measures and emits the same position. */
#ifndef ISM_STRADDLE_H
#define ISM_STRADDLE_H

#include <stdbool.h>
#include "core/mesh/mesh.h"
#include "core/octree/cell_types.h"
#include "core/octree/sampler.h"

/* shift: the distance a vertex moves (0: none); box: the request's box (lo xyz, hi xyz),
 * whose faces' vertices stay where they are. Writes p moved (or p itself) to q; true when
 * it moved. */
bool ism_straddle_point(ism_sampler *s, double shift, const double box[6], const double p[3],
                        double q[3]);

/* As ism_straddle_point, at saddles and parabolic points too: a chord of length L along a
 * tangent direction where f's tangential Hessian over |∇f| is l lies l L² / 8 below the
 * surface (along ∇f), l between the eigenvalues l2 <= l1. A move by d along ∇f leaves the
 * chords within s (l1 - l2) / 2 of the surface (s = L² / 8) when d = s (l1 + l2) / 2, so
 * with d = E (l1 + l2) / (l1 - l2), capped at ±shift, the chords meet E up to s = 2 E /
 * (l1 - l2) (saddles: sag room 1/(1 - r) times the unmoved vertex's, r the capped ratio)
 * and up to (E + shift) / l1 where the cap binds (one-way bending: the move above). A pure
 * function of the point, like the move above. bend (may be NULL): the surface's largest
 * principal curvature at p in magnitude (max(|l1|, |l2|) of the tangential Hessian over
 * |∇f|), from the same Hessian; 0 where the move does not look (shift 0, a face of the box,
 * no usable Hessian). */
bool ism_straddle_balanced_point(ism_sampler *s, double shift, const double box[6],
                                 const double p[3], double q[3], double *bend);

/* f, ∇f and the Hessian (xx xy xz yy yz zz) at a point, as ism_eval_hessian gives them. */
typedef struct ism_straddle_jet {
    double f, g[3], h[6];
} ism_straddle_jet;

/* ism_straddle_balanced_point with f's jet at p taken beforehand (j: bit for bit
 * ism_eval_hessian's at p on s's tape, e.g. by ism_eval_hessian_batch; NULL: evaluated
 * here): the same answer and the same count of gradients. bend (may be NULL): bend[0] as
 * ism_straddle_balanced_point's, bend[1] the least principal curvature in magnitude
 * (min(|l1|, |l2|) / |∇f|) where both bend one way (l1 l2 > 0), else 0 — every chord
 * through p, whatever its direction, bends at least that much. */
bool ism_straddle_balanced_point_at(ism_sampler *s, double shift, const double box[6],
                                    const double p[3], const ism_straddle_jet *j, double q[3],
                                    double bend[2]);

/* The distance to f = 0 (refine.h's measure, every point) of out's triangles from first_tri
 * on with the vertices from first_vert on moved; out is left as it was. False when out of
 * memory. */
bool ism_straddle_emitted_error(ism_sampler *s, double shift, const double box[6],
                                ism_cell_out *out, size_t first_vert, size_t first_tri,
                                double *err);

/* Every vertex of a finished mesh moved (the positions the nodes were measured with). */
void ism_straddle_mesh(ism_sampler *s, double shift, const double box[6], ism_mesh *m);

/* The shift for bound E on tape t: STRADDLE_SHARE × E where the move applies (a tape without
 * min/max, whose creases the move would blur; no singular locus known), else 0. */
double ism_straddle_shift(const ism_tape *t, double max_error, bool has_locus);

#endif
