/* rm_brec.h — what the quality pass under an error bound knows of each triangle's centroid
 * and edge midpoints without measuring them again, and of each vertex's offset (rm_brec.c).
 * Under max_error every move of a vertex has its fan's new centroids and the midpoints of
 * the edges at the vertex measured with a Newton step (rm_bound.h): 739M of the gyroid-ball
 * pass's 1,974M instructions at the default bound (callgrind), against 1,406M for the
 * polygonisation. Each triangle keeps, for its centroid and for the midpoint of each of its
 * edges, the last point measured there and an upper bound u on that point's distance to
 * f = 0 (rm_bound_upper: the two-step measure, or one step and its residual). The distance
 * to a set moves by at most as far as the point moves, so a point s from a kept one lies
 * within u + s; the pass's measure reads within ISM_RM_CBOUND_RATIO of the distance (the
 * unbounded record's premise, rm_cbound.h), so when that ratio times u + s is within
 * max_error the point would measure within it too and is not measured (it then keeps
 * u + s). Not exact in principle, as rm_cbound.h; measured: no decision changed on 33
 * preset runs (core/README.md; test remesh/bounded_record_leaves_the_reference_mesh, which
 * fails without the ratio). A record says something about its point only, whatever the
 * mesh did since: a slot whose point is not the one asked about knows nothing. A record also
 * keeps the unit normal of f's level set where its point was measured: a relaxation moves the
 * fan's points along the surface, and with f's unit normal turning by at most κ per unit
 * length about the fan the bound grows by the move's normal part and the square of its
 * length rather than by its whole length (rm_brec.c's moved_bound; not where the fan has a
 * protected vertex). κ is certified: |H|_F / |∇f| over a box holding the fan grown by
 * max_error, from f's interval jet (rm_brec.c's box_bend; none where ∇f may vanish or a
 * min/max may switch branches in the box). Until session 18 it was twice the turn of the
 * vertices' sampled normals per unit length, which a bend narrower than an edge between them
 * escapes (test remesh_brec/a_bump_between_the_vertices_is_not_carried_over: a centroid
 * 3.5 E off the surface was taken as within E). gyroid-ball, default bound: pass 1,538M ->
 * 1,437M instructions with the sampled turn, the same meshes. The boxes cost more than they
 * spare on every preset measured, so the bent bound is asked only while its first boxes pay
 * (RM_BREC_BEND_TRIAL). Only for the quality pass (the simplification keeps its own
 * measures, rm_memo.h), and only where f cannot crease (remesh.c: across a min/max crease
 * the measure jumps by more than the point moved, and the ratio does not cover it). */
#ifndef ISM_RM_BREC_H
#define ISM_RM_BREC_H

#include "core/remesh/rm_pass.h"

/* Room for every triangle and vertex the pass may hold (r.cap_tris, r.cap_verts): no
 * triangle's point known yet, every vertex's offset where it stands (rm_normals'
 * found_offset, taken and freed). False when out of memory. rm_pass_close frees it. */
bool rm_brec_open(rm_pass *p);

/* Doubles per vertex of rm_pass.bend: a box (low corner, high corner) and how fast f's unit
 * normal may turn in it (rm_brec.c's fan_bend). */
#define RM_BREC_BEND_REC 7
/* fan_bend (rm_brec.c) bounds the normal's turn over a box about v's fan grown by this share
 * of its largest side each way, kept for v: a relaxation moves vertices by fractions of an
 * edge, so later checks of v's fan find their box inside and ask no interval jet again; a
 * larger box bounds the turn more loosely (its interval enclosures widen). callgrind, default
 * bound, pass instructions at 0.1 / 0.25 / 0.5 / 1: gyroid-ball 1,766M / 1,763M / 1,725M /
 * 1,724M, klein-bottle 948M / 917M / 902M / 898M; sphere and torus within 0.1%. */
#define RM_BREC_BOX_GROW 0.5
/* A new box's bound costs f's interval gradient over it, and its interval jet where that
 * leaves ∇f bounded away from 0 with no kink: gyroid-ball ~7,500 + ~11,700 instructions,
 * against ~1,050 for an evaluation and gradient at a point (~1,500 with the measure's
 * bookkeeping); torus ~3,000 against ~390. Once RM_BREC_BEND_TRIAL boxes have been worked
 * out, if the bent bound has spared fewer than RM_BREC_BEND_MIN_SPARED points per box where
 * the plain bound could not, the bent bound is not asked for the rest of the pass (the plain
 * bound alone; records then keep no normal, which serves nothing else). Stopping only new
 * boxes, with the ask and the normals kept, cost gyroid-ball 42M more than no box at all.
 * Measured (callgrind, default bound, session 19): points so spared per box gyroid-ball 0.6
 * (9,933 boxes, 8 in 10 infinite beside the crease), sphere 3.4, torus 0.4 (half of its
 * boxes leave |∇f| unbounded from 0: the quartic's enclosures), klein-bottle 0.25. With
 * the rule (and RM_BREC_TRIAL 512) the pass costs gyroid-ball 1,643M -> 1,579M instructions,
 * sphere 11.70M -> 11.63M, the same meshes (no box at all, normals kept: 1,601M, 11.47M).
 * 4 points a box: about where a box's gradient pays for itself in evaluations spared. The
 * trial keeps the certified bend at work where boxes are few or pay (test
 * remesh_brec/a_bump_between_the_vertices_is_not_carried_over works out one). */
#define RM_BREC_BEND_TRIAL 64
#define RM_BREC_BEND_MIN_SPARED 4.0

/* A record not measured at its point (a bound carried by moved_bound) keeps its normal while
 * the normal may have turned by at most this (radians) since it was measured; beyond, it
 * keeps the bound that needs no normal and the point is measured the next time the records
 * do not hold it. Chains of carried bounds are where the measure strays from the distance:
 * on the gyroid-ball at its default bound the meshes are byte-identical to measuring every
 * point (measure_all_centroids) with 0.05 and 0.1, one decision differs with no limit (a
 * normal carried through a turn of 0.107 beside the crease, the point measured 0.0057
 * against a bound of 0.0024). 0.05 spares 99M of the pass's 1,538M instructions there. */
#define RM_BREC_TURN_MAX 0.05

/* True when v's fan with v at x lies within max_error (through the records when they are
 * open, else measured: rm_bound_fan_worst), or no farther than with v where it is (a fan the
 * polygoniser left beyond the bound may still improve). */
bool rm_bound_fan(rm_pass *p, uint32_t v, const double *x);

/* True when v's fan with v at x lies within max_error: x, every centroid and the midpoint of
 * every edge at v (v free: a closed fan), each bounded by what its triangle knows or else
 * measured (rm_bound_upper), in rm_bound_fan's order. What it finds is kept for the move
 * (rm_brec_moved). */
bool rm_brec_fan_within(rm_pass *p, uint32_t v, const double x[3]);

/* The records cost a lookup, a distance and the bookkeeping per point (~100 instructions),
 * worth it where they spare an evaluation often enough: gyroid-ball (f with six sines and
 * cosines, ~1,050 instructions an evaluation and gradient) takes 34% of the fan's points from
 * them; the dual meshes of the sphere and torus (~100-400 instructions an evaluation, their
 * balanced centroids near the bound) 6% and fewer, and the torus's pass grew from 86.1M to
 * 91.2M instructions with them. Once RM_BREC_TRIAL points have been asked of a record that
 * held them, and fewer than RM_BREC_MIN_SHARE of them were spared, the records are dropped
 * for the rest of the pass (the decisions are the same either way). The share counts what the
 * plain bound (u + |δ|, moved_bound) spares, the measure the threshold was set on: the bent
 * bound spares more on every surface, and counted in, the torus kept its records (its pass
 * 86.6M -> 99.8M instructions, where an evaluation costs ~390). The trial was 2,048 points
 * until session 19; 512 decides the same way on gyroid-ball (kept: 4 in 10 spared) and costs
 * the surfaces where they do not pay a quarter as much: pass instructions, default bound,
 * sphere 13.30M -> 11.70M, torus 88.70M -> 86.81M, pretzel-genus2 76.61M -> 74.47M,
 * cube-minus-ball 1,427M -> 1,424M, the same meshes; klein-bottle's records, kept at 2,048
 * though they did not pay there, are dropped: 689M -> 640M (with the bend's rule above, at
 * 2,048 657M). */
#define RM_BREC_TRIAL 512
#define RM_BREC_MIN_SHARE 0.15
/* True while the records are kept (rm_bound_fan asks before each check); frees them when
 * they have not paid (above). */
bool rm_brec_pays(rm_pass *p);

/* The largest bound the records give v's fan where it is (INFINITY when one is not known). */
double rm_brec_fan_known(const rm_pass *p, uint32_t v);

/* v moves to x: the records of its fan take what rm_brec_fan_within found for x. */
void rm_brec_moved(rm_pass *p, uint32_t v, const double x[3]);
/* What rm_brec_fan_within found is for no move. */
static inline void rm_brec_drop(rm_pass *p) { p->cen_keep_v = UINT32_MAX; }

/* The signed distance rm_bound_signed measures at v's place: as kept for that place
 * (rm_brec_open, on the bounded records' path: every vertex's place as the pass found it;
 * rm_brec_offset_set), bit for
 * bit what it would measure (f is pure), or measured. A relaxation move keeps a vertex's
 * offset off f = 0 (rm_relax.c): each of the gyroid-ball's 73,631 moves tried asked it
 * where the vertex stood (97M instructions), though only its own moves change it. */
double rm_brec_offset(rm_pass *p, uint32_t v);
/* v is to be at x (rm_commit_move): its offset there is kept (a lookup when x was just
 * measured; nothing without records). */
void rm_brec_offset_set(rm_pass *p, uint32_t v, const double x[3]);

#endif
