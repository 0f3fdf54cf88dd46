/* rm_pass.h — the state one quality pass shares between its steps (remesh.c sequences them):
 * the incidence, f and a workspace to evaluate it, unit normals from ∇f at the vertices, and
 * the steps themselves: protection (rm_locks.c), Lawson flips (rm_flip.c), edge collapses
 * (rm_collapse.c), tangential relaxation with projection onto f = 0 (rm_relax.c), box
 * boundary slides (rm_slide.c), and the renumbering that drops what collapses removed
 * (rm_compact.c). */
#ifndef ISM_RM_PASS_H
#define ISM_RM_PASS_H

#include "core/eval/eval.h"
#include "core/remesh/remesh_types.h"
#include "core/remesh/rm_mesh.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>

/* |∇f| at most this × the median over the vertices counts as vanishing (a singular point or
 * curve: no tangent plane to move in; the analysis's singular_rel). */
#define ISM_RM_SINGULAR_REL 1e-6
/* A fan whose smallest angle is at least this (degrees) needs no work: a move may lower a
 * fan's smallest angle while it stays at or above it (evening out sizes lowers good angles
 * a little to raise bad ones nearby), and vertices far from any triangle under it are not
 * relaxed at all. */
#define ISM_RM_COMFORT_DEG 35.0
/* Dihedral (between the normals of an edge's two triangles) above which the edge is a crease
 * of the surface: the polygoniser's meshes bend by a few degrees per edge on smooth parts
 * (about 4° on the sphere preset, rarely 25° on tight curvature), while a max/min crease
 * meets at tens of degrees. Neither flipped across nor moved
 * along (rm_locks.c), but for a crease vertex sliding along its crease (rm_crease_slide.c). */
#define ISM_RM_CREASE_DEG 40.0
/* Its cosine, the one number every crease test compares a dot product of unit normals with
 * (rm_sheets.c's grouping and the screen before it agree through it; GCC folds it to a
 * constant, revE 5). */
static inline double rm_crease_cos(void)
{
    return cos(ISM_RM_CREASE_DEG * M_PI / 180);
}
/* Triangles whose smallest angle is under this (degrees) have their edges tried by the
 * collapses (rm_collapse.c): the goal on smooth surfaces; better triangles are left to
 * flips and relaxation. */
#define ISM_RM_COLLAPSE_DEG 20.0

/* A merge along a crease (rm_collapse.c, rm_crease_slide.c) that leaves fewer triangles
 * under ISM_RM_COLLAPSE_DEG may lower its fan's smallest sine to this share of it (the
 * collapses' own rule: it must grow). gyroid-ball needles under 10° in bench_remesh's boxes
 * 157 / 155 / 207 -> 115 / 113 / 149, its smallest angle 0.53 / 0.41 / 0.27° -> 0.66 / 0.66 /
 * 0.40° (rm_collapse.c's merges). */
#define ISM_RM_CROWD_SINE_FLOOR 0.5

/* A removed vertex, and the kept one after the merge, have at most this many triangles
 * (rm_collapse.c's collapses, rm_crease_slide.c's merges onto a crease): higher valences
 * make poor angles anyway. */
#define ISM_RM_COLLAPSE_MAX_DEGREE 16
/* A new triangle facing more than this from the old fan's normal is a fold (the relaxation's
 * limit, ISM_RM_MAX_TURN_DEG in rm_relax.c); across a crease (rm_crease_tri_ok) the limit
 * is against the triangle's own normal before, the fan's mean normal saying nothing there. */
#define ISM_RM_COLLAPSE_MAX_TURN_DEG 60.0
/* A triangle beside a crease may face within this (degrees) of one branch's normal there
 * (∇f of that sheet), whatever it faced before: a fan moved onto the crease
 * (rm_crease_slide.c's tri_ok) and the cone of a junction's collapse (rm_junction.c, whose
 * 1e-4 triangles' normals before are noise). A chamfer triangle between the two surfaces
 * faces neither, and turns by up to the crease's angle (140° on the cube-minus-ball) once its
 * corner is on the crease; 60° is the turn limit's own (ISM_RM_COLLAPSE_MAX_TURN_DEG).
 * bench_remesh cube-minus-ball, 0.37-cell box: 359 needles with the turn limit alone, 174
 * with 30°, 119 with 45°, 108 with 60°; gyroid-ball own / 1e-3 / 0.37-cell / √2−1 boxes
 * 19 / 22 / 35 / 23 with 45°, 19 / 20 / 24 / 19 with 60°. */
#define ISM_RM_CREASE_FACE_DEG 60.0
/* A merge or move along a crease (rm_crease_tri_ok) may bend a new triangle against its
 * outer neighbour by this much (degrees) more than before, beyond the crease angle: at a
 * crease the outer edge may be the crease's own, bending by tens of degrees, and moving a
 * vertex by a hair (or along a curved crease) changes that by a little either way. */
#define ISM_RM_CROWD_BEND_DEG 10.0
/* A vertex is on a crease when both of its functions (a min/max's branches, or two of f's
 * pieces) measure within this × the mean edge of 0 (|a| / |∇a|, first order), and Newton
 * onto the crease stops there and takes one step more (rm_crease_slide.c, rm_junction_fan.c;
 * the gyroid ball's moved vertices: under 2e-11 from either surface by their closed forms);
 * the polygoniser's edge roots beside the crease lie 1e-5 of an edge and more off. */
#define ISM_RM_CREASE_ON_REL 1e-9
/* Minimum-norm Newton steps onto a = b = 0 at most (quadratic: from a fraction of an edge
 * off, 3-4 reach ISM_RM_CREASE_ON_REL). */
#define ISM_RM_CREASE_NEWTON_STEPS 8
/* The two functions' gradients count as parallel (the crease not transversal: no curve to
 * slide on) when the 2 × 2 normal system's determinant is under this share of its diagonal's
 * product (crease_split.c's rule: a crossing angle under 1e-6 rad). */
#define ISM_RM_CREASE_PARALLEL 1e-12
/* A crease vertex nearer a neighbour than this × its mean edge crowds the crease: merged
 * into it (rm_collapse.c; on a min/max crease, where both go onto a = b = 0, farther
 * neighbours merge too: rm_crease_slide.c ISM_RM_CREASE_MERGE_REL), the crease moves by at most that much (the gyroid ball's crease vertices 1/20 to 1/400
 * of a cell apart, its edges about a cell; while a merge also asked for exactly two crease
 * edges at v, 0.1 left 246 / 245 / 335 needles in bench_remesh's boxes, 0.25 240 / 239 /
 * 321). */
#define ISM_RM_CROWD 0.25
/* A vertex slid along a curve (rm_slide.c's box boundaries, rm_crease_slide.c's creases)
 * is refused outside this fraction of the span between its two neighbours on the curve
 * (measured along their chord): the curve stays in order with room to spare. */
#define ISM_RM_SLIDE_KEEP_ORDER 0.05

typedef struct rm_pass {
    rm_mesh r;
    const ism_tape *f;
    ism_eval_ws *ws;
    double *normal;        /* 3 per vertex: ∇f / |∇f| (0 where it vanishes) */
    double gthresh;        /* |∇f| at or below this vanishes */
    double max_error;
    bool may_crease;       /* f's gradient may jump across a curve of f = 0 (rm_pass.c's
                              may_crease): without that no edge is a crease */
    uint8_t *active;       /* per vertex: relaxed in this round (near a poor triangle) */
    uint8_t *slide;        /* per vertex: on a box face's boundary curve, may slide along it */
    uint8_t *touched;      /* per vertex: near a collapse of this sweep (rm_collapse.c), or
                              a corner of a split needle (rm_insert.c) */
    double centroid_bound;  /* collapses may put a centroid this far from f = 0 (the mesh's
                               farthest before the pass, at most max_error) */
    double midpoint_bound;  /* the same for edge midpoints, measured on the mesh as found
                               (found_*) when first needed (rm_midpoint_within) */
    double midpoint_low;    /* at most midpoint_bound: the farthest midpoint of the
                               triangles with the farthest centroids (rm_collapse_bounds) */
    bool midpoint_known;    /* midpoint_bound has been measured */
    bool bounds_known;      /* centroid_bound and midpoint_low have been measured
                               (rm_collapse_bounds_need) */
    const double *found_pos; /* the mesh as the pass found it (the caller keeps it) */
    const uint32_t *found_tri;
    size_t found_ntris;
    bool bounded;           /* the rule under max_error (rm_bound.h; the simplification, and
                               the quality pass given a bound): flips and moves keep every
                               centroid and edge midpoint within max_error, measured with a
                               Newton step, whatever they were before; collapses, insertions
                               and slides measure with the step too, midpoints included */
    struct rm_memo *memo;   /* distances measured by point (rm_memo.h; NULL: none kept) */
    struct rm_hcell *hcell; /* Hessian bounds by grid cell (rm_hcell.h), in the quality pass
                               under a bound: a measure against a finite limit may leave out
                               its second evaluation (NULL: both taken) */
    uint8_t *flipped;       /* per vertex, when not NULL: set on the four corners of every
                               flip (remesh.c asks, to look at only their protection again) */
    double poorest;         /* the smallest sine of a triangle's smallest angle when
                               rm_mark_active last looked: flips, moves and collapses never
                               make a triangle worse than that, so while it is at least
                               sin(ISM_RM_COLLAPSE_DEG) there is no needle to mend */
    size_t poor;            /* the triangles under ISM_RM_COLLAPSE_DEG then */
    bool bend_curvature;    /* collapses accept a new bend that f's curvature accounts for
                               (rm_collapse.c; the last mending only: remesh.c) */
    double relax_min_step;  /* a relaxation step shorter than this × the fan's mean edge is
                               not tried (rm_relax_vertex; 0: every one) */
    double relax_far_step;  /* the same for a vertex no corner of whose fan is locked,
                               with no needle among the triangles at those corners (two
                               rings of triangles) and farther than
                               ISM_RM_FAR_POINT_EDGES mean edges from every given point
                               (rm_relax.c's far_from_points; rm_relax_vertex; remesh.c's
                               ISM_RM_FAR_STEP; at least relax_min_step) */
    const double *points;   /* the given singular points (3 per point: ism_remesh_options'
                               locked_points), near which no vertex takes the far step */
    size_t npoints;
    double *sine;           /* per triangle, or NULL: the sine of its smallest angle as
                               rm_mark_active last measured it (NAN: its shape changed
                               since, rm_shape_changed) */
    uint8_t *obtuse;        /* per triangle, or NULL: bit k set when its corner k's angle is
                               not acute (rm_flip.c's obtuse_edges), RM_OBTUSE_UNKNOWN when its
                               shape changed since (rm_shape_changed) */
    double *crease_tried;   /* per vertex, or NULL: its fan's sines summed when
                               rm_crease_slide_sweep last asked it and nothing passed (NAN:
                               not asked): a fan that has not changed fails again */
    double *cen_ref;        /* RM_CBOUND_REC per triangle, without an error bound
                               (rm_cbound.h): a point last measured at its centroid, the
                               distance there (INFINITY: none) and |∇f| there */
    double *cen_keep;       /* what a fan's check found for a move not yet made:
                               RM_CBOUND_REC or, under a bound, KEEP_REC (rm_brec.c) per
                               triangle */
    uint32_t cen_keep_cap, cen_keep_v; /* its room; the vertex (UINT32_MAX: none kept) */
    double cen_keep_x[3];   /* where that vertex would go */
    double cen_gradient_min; /* |∇f| below which a record bounds nothing (rm_cbound.h) */
    double *brec;           /* RM_BREC_REC per triangle, under an error bound in the quality
                               pass (rm_brec.c): its centroid's and edge midpoints' last
                               points measured and bounds on their distances */
    double *offset;         /* 4 per vertex under an error bound: a place and rm_bound_signed
                               there (rm_offset_open) */
    double *found_offset;   /* per vertex of the mesh found, or NULL: rm_bound_signed at
                               its place then, from rm_normals' evaluation (rm_offset_open
                               takes them into offset and frees this; a pass that keeps no
                               offsets frees it at once, rm_found_offset_drop) */
    size_t found_offset_n;  /* vertices found_offset holds: the mesh's count then */
    size_t brec_known, brec_skipped; /* points whose slot held them, and of those the ones
                                        the plain bound spares (rm_brec_pays) */
    double *bend;           /* RM_BREC_BEND_REC per vertex, with brec: a box about its fan and
                               a certified bound on how fast f's unit normal turns in it
                               (rm_brec.c's fan_bend; NAN: none yet) */
    struct ism_ivjet_ws *jws; /* f's interval jets (interval_jet.h), for bend */
    size_t bend_boxes;      /* boxes bend was worked out for */
    size_t bend_spared;     /* points the bent bound spared where the plain one could not */
    bool bend_stopped;      /* the bent bound no longer asked: its first boxes did not pay
                               (rm_brec.h RM_BREC_BEND_TRIAL) */
    size_t flips, moves, collapses, inserts;
} rm_pass;

/* Opens a pass over m (the caller keeps m): f's workspace, the incidence with room for extra
 * vertices (and 2 × extra triangles), the marks, ∇f's unit normals and the protection. False
 * when out of memory or f is missing; rm_pass_close must be called either way. */
bool rm_pass_open(rm_pass *p, ism_mesh *m, const ism_remesh_options *o, size_t extra);
/* Drops what collapses removed from m (which had nverts_before and ntris_before vertices and
 * triangles when the pass opened; ren, may be NULL, gets the maps) and frees the state.
 * False when out of memory (m is still valid). */
/* Every vertex's signed distance kept with its place in p->offset (rm_brec_offset reads it
 * while the vertex stands there), first from rm_normals' found_offset, which it frees: the
 * moves under a bound then measure no vertex where it stood. False when out of memory
 * (offset NULL: each measured when asked). */
bool rm_offset_open(rm_pass *p);
bool rm_pass_close(rm_pass *p, size_t nverts_before, size_t ntris_before,
                   ism_remesh_renumber *ren);

/* Room for insertions (rm_insert.c): at most ntris / ISM_RM_INSERT_SHARE + ISM_RM_INSERT_MIN
 * vertices per pass, and one more for each triangle of the mesh as found whose smallest angle
 * is under ISM_RM_INSERT_DEG (remesh.c). Steiner's box needs about 300 for its 64,000
 * triangles; beside a double curve whose vertices lie closer than its sheets' triangles are
 * wide every needle takes one: whitney-umbrella's 1e-3 box took the 164 of the fixed share and
 * left 320 needles on its double line, and with room takes 518 (of 904 raw needles) and leaves
 * 1. A mesh without needles reserves what it did. */
#define ISM_RM_INSERT_SHARE 32
#define ISM_RM_INSERT_MIN 64
/* Needles under this smallest angle (degrees) are mended by insertion: the count the issue
 * measures; between it and 20° the flips and moves do well enough. */
#define ISM_RM_INSERT_DEG 10.0

/* Unit normals and the vanishing threshold from ∇f at every vertex. False when out of memory. */
bool rm_normals(rm_pass *p);
/* The offsets rm_normals kept, freed: for a pass that keeps no offsets (rm_offset_open). */
static inline void rm_found_offset_drop(rm_pass *p)
{
    free(p->found_offset);
    p->found_offset = NULL;
    p->found_offset_n = 0;
}

/* Marks protected vertices (r.locked) and collects the given locked edges. False when out of
 * memory. */
bool rm_lock_features(rm_pass *p, const ism_remesh_options *o);

/* The vertex a given point pins (RM_PINNED): the nearest to x used by some triangle
 * (UINT32_MAX when none). */
uint32_t rm_point_vertex(const rm_mesh *r, const double *x);

/* Recomputes the vertex protection (r.locked, slide) from the mesh as it is now: after flips
 * have replaced caps, whose noisy normals looked like creases. Features that flips never
 * change (boundary, non-manifold, labels, locked edges and points) stay protected. With
 * only, just the vertices it marks (whose fans changed) are looked at again. */
void rm_lock_vertices(rm_pass *p, const ism_remesh_options *o, const uint8_t *only);

/* ∇f and the Hessian at the vertices, each evaluated once while the vertices stay where
 * they are (one protection pass: an edge is judged from both its ends). */
typedef struct rm_curvature_memo {
    double *gh;    /* 9 per vertex: ∇f, then the Hessian (xx xy xz yy yz zz) */
    uint8_t *have; /* per vertex: gh holds it */
} rm_curvature_memo;

/* Room for nverts vertices; without it (out of memory) the memo is empty and every lookup
 * evaluates. rm_curvature_memo_close frees it either way. */
void rm_curvature_memo_open(rm_curvature_memo *memo, size_t nverts);
void rm_curvature_memo_close(rm_curvature_memo *memo);

/* True when the bend (radians) between two triangles on the edge of vertices a and b, whose
 * heights over ab sum to width, is no more than f's curvature turns its normal across ab over
 * that width (rm_crease.c): the surface bends there, no crease is there. memo may be NULL. */
bool rm_bend_is_curvature(const rm_pass *p, uint32_t a, uint32_t b, double bend, double width,
                          rm_curvature_memo *memo);

/* True when edge {a, b} is free: an oriented manifold edge, one label, not locked, no crease. */
bool rm_edge_free(const rm_pass *p, uint32_t a, uint32_t b);

/* Lawson flips starting from the edges of triangles with an active vertex, each flip
 * queueing its quad's four sides; returns the flips made. *ok false when out of memory. */
size_t rm_flip_active(rm_pass *p, bool *ok);
/* The same, starting from the edges of triangles with a vertex marked in seed. */
size_t rm_flip_from(rm_pass *p, const uint8_t *seed, bool *ok);

/* The geometric tests a flip of AB to CD in the triangles (A, B, C), (B, A, D) must pass
 * (the Delaunay test, bends, facing, smallest angle, distances): for a quad that does not
 * exist yet (rm_insert.c asks before splitting). */
bool rm_flip_would_pass(rm_pass *p, const double *A, const double *B, const double *C,
                        const double *D);

/* Triangle t, whose corners are o[] before and q[] after a merge or move along a crease,
 * keeps its outer edge {a, b} (the one not at the vertex moved): q's normal stays within
 * ISM_RM_COLLAPSE_MAX_TURN_DEG of o's (its own before: across a crease the fan's mean
 * normal says nothing), and against the triangle across ab (rm_merge_across; none: no
 * test) q bends by at most the crease angle or by ISM_RM_CROWD_BEND_DEG more than o did.
 * A degenerate q or o fails (rm_collapse.c). */
bool rm_crease_tri_ok(const rm_pass *p, uint32_t t, uint32_t a, uint32_t b,
                      const double *o[3], const double *q[3]);
/* rm_crease_tri_ok's bend part: new triangle t (normal n, length ln; m / lo its normal
 * before) bends against the triangle across its outer edge a -> b by at most the crease
 * angle or by ISM_RM_CROWD_BEND_DEG more than before, or (curvature) by what f's curvature
 * explains (rm_bend_is_curvature); true where ab is no manifold edge. rm_junction.c's cone
 * triangles, which face their sheet's ∇f instead, share it. */
bool rm_crease_bend_ok(const rm_pass *p, uint32_t t, uint32_t a, uint32_t b, const double *n,
                       double ln, const double *m, double lo, bool curvature);

/* Collapses edges of triangles with a small angle (rm_collapse.c) where the topology, the
 * features and the distance to f = 0 allow it; returns the collapses made. Removed
 * triangles are marked dead and removed vertices gone (rm_compact drops them). *ok false
 * when out of memory. */
size_t rm_collapse_active(rm_pass *p, bool *ok);
/* No new centroid or new edge's midpoint of merging g->v into g->w (rm_merge.h) farther from
 * f = 0 than the farthest of the old fan's centroids, resp. midpoints of v's edges, or than
 * the mesh's farthest before the pass (within the error bound): the collapses' rule
 * (rm_collapse.c), which the horn tips' merges share (rm_horn.c). */
struct rm_merge;
bool rm_merge_distance_ok(rm_pass *p, const struct rm_merge *g);
/* rm_merge_distance_ok's rule on figures measured elsewhere: new_c / new_m the farthest new
 * centroid / midpoint from f = 0, old_c / old_m the farthest there before (asked only when
 * rm_distances_within does not decide); rm_junction.c's collapses share it. The verdict
 * reads only the found mesh and the figures given, never which merges came before. */
bool rm_distances_within(rm_pass *p, double new_c, double new_m);
bool rm_distances_ok(rm_pass *p, double new_c, double new_m, double old_c, double old_m);
/* Merges g->v into g->w, marking the corners of its new triangles active and touched (their
 * shapes changed); the new triangles into fan (room for ISM_RM_MERGE_MAX_DEGREE), *nfan how
 * many. False when out of memory (nothing changed). */
bool rm_merge_do(rm_pass *p, const struct rm_merge *g, uint32_t *fan, uint32_t *nfan);
/* Merges the rings of thin tubes that end at a given point (the horn cyclide's horns) into
 * the point's vertex, tip first, where a needle lies on the tube (rm_horn.c); returns the
 * merges made (they count in collapses). *ok false when out of memory. */
size_t rm_horn_tips(rm_pass *p, const ism_remesh_options *o, bool *ok);
/* Collapses the crowds of locked crease vertices that needles under 10° still join (where
 * two or more crease sheets meet: a cube's corner, three balls' triple points, and along
 * the creases beside them), each into one of its vertices, where the star stays a disc and
 * every new triangle keeps to its own sheet (rm_junction.c); returns the collapses made
 * (they count in collapses). *ok false when out of memory. */
size_t rm_junction_collapse(rm_pass *p, bool *ok);
/* Where a junction's vertex J (rm_junction_vertex_on) keeps a needle J–c–w with c a crowd
 * vertex on one crease a hair from J and no vertex on another crease beside it: the vertex
 * across c–w goes onto that crease, c slides out along its own and c–w flips to the
 * junction, measured as one operation and undone unless J's smallest angle grows with none
 * about it thinner or farther from f = 0 (rm_junction_fan.c). Returns the operations kept
 * (they count in flips). *ok false when out of memory. */
size_t rm_junction_fan_mend(rm_pass *p, bool *ok);

/* Two functions' values and gradients at x (false: not defined there). */
typedef bool (*rm_two_eval)(void *ctx, const double x[3], double val[2], double g[2][3]);
/* Newton from x onto ev's common zero (rm_newton2.c): true when both values came within tol ×
 * their gradients' lengths of 0 within ISM_RM_CREASE_NEWTON_STEPS steps; x then has taken one
 * minimum-norm step more (none where the gradients are parallel) and g holds the gradients
 * measured before that step. False when a value is not finite or it does not get there. */
bool rm_newton_two(rm_two_eval ev, void *ctx, double x[3], double tol, double g[2][3]);
/* The sheets that ∇f's unit normals at some vertices fall into, each group's first normal
 * and its tangent plane's offset (n · x at that vertex): a normal more than the crease angle
 * (ISM_RM_CREASE_DEG) from every group's starts a new one. Two on a crease, three or more at
 * a junction. rm_junction.c's clusters read it, and rm_junction_vertex for the crease merges
 * (crease_merge_find, rm_collapse.c; snap_merge, rm_crease_slide.c). rm_sheets.c. */
typedef struct rm_sheets {
    const double *normal[ISM_RM_COLLAPSE_MAX_DEGREE];
    double d[ISM_RM_COLLAPSE_MAX_DEGREE];
    uint32_t v[ISM_RM_COLLAPSE_MAX_DEGREE]; /* each group's first vertex */
    int n;
} rm_sheets;
/* Adds v's normal to s (none where ∇f vanishes at v; none past ISM_RM_COLLAPSE_MAX_DEGREE
 * groups). */
void rm_sheets_add(const rm_pass *p, rm_sheets *s, uint32_t v);
/* True, x the point where the first three sheets' tangent planes meet, when s has three or
 * more and their normals span space enough for that point to be a junction
 * (ISM_RM_JUNCTION_DET); then taken on to where f's three smooth pieces there (eval.h
 * ism_piece, each at its group's first vertex) all vanish, by Newton steps from it, when
 * those converge (rm_sheets.c: a curved sheet's plane read 0.1 from the junction misses it
 * by ~0.007 on three-balls). */
bool rm_sheets_meet(const rm_pass *p, const rm_sheets *s, double x[3]);
/* v is a junction's vertex: the ∇f normals at v and the vertices up to two edges from it fall
 * into three sheets or more whose tangent planes (each through the sheet's vertex nearest v)
 * meet at a point (rm_sheets_meet, taken on to the pieces' common zero) within v's mean edge,
 * and v is nearer that point than each neighbour. Two edges: in a crowd the junction's own fan
 * may be three triangles to crease vertices whose ∇f shows only two of the sheets (a crease
 * vertex's normal is one branch's; three-balls' own box, upper triple point). The polygoniser
 * puts a vertex on such a point (three balls' triple points, a cube's corners: within 1e-8).
 * The crease merges keep it: crease_merge_find (rm_collapse.c) does not merge it away,
 * rm_crease_slide.c does not move it as the vertex that stays and, when it lies on the point
 * (rm_junction_vertex_on), merges its crowd into it where it is rather than it into them and
 * does not slide it; rm_junction.c's clusters that hold it on the point collapse into it
 * alone. False, without looking, for v of more than ISM_RM_MERGE_MAX_DEGREE
 * triangles (rm_merge.h): such a vertex is not recognised as a junction's (crease_merge_find
 * does not merge a vertex of that degree anyway; snap_merge may then move it as the vertex that
 * stays). */
bool rm_junction_vertex(const rm_pass *p, uint32_t v);
/* A vertex within this × its mean edge (rm_junction_vertex_on; rm_junction.c: × the
 * cluster's reach) of where the sheets meet (rm_sheets_meet: f's three pieces' common zero,
 * to rounding) lies on the junction: the polygoniser puts a vertex there within 1e-8 of the
 * box diagonal (three-balls: 4.4e-9, edges 0.006 at depth.max 7, 0.1 at 5), the crowd round
 * it lies 1e-5 of an edge and more off (0.0004-0.0025 on three-balls), and without a bound
 * the cube's nearest vertex to a corner, taken for its junction's by rm_junction_vertex,
 * 0.0066 off (edges ~0.02). Only a vertex on the point is kept from every merge and slide:
 * keeping the one nearest the corner in that unbounded cube took its smallest angle from
 * 15.01° to 10.87°; and a cluster holding it collapses into it alone (three-balls at
 * depth.max 5, 1e-3 box: its upper triple point collapsed into a crowd vertex 0.0017 off it
 * for a cone of 1.05° against 0.86° into it). */
#define ISM_RM_JUNCTION_AT 1e-4
/* rm_junction_vertex, and v on the point (within ISM_RM_JUNCTION_AT × its mean edge). */
bool rm_junction_vertex_on(const rm_pass *p, uint32_t v);
/* rm_junction_vertex without its screen (third_sheet_possible, which only says no where the
 * grouping would): the tests' check that the screen changes no answer. */
bool rm_junction_vertex_unscreened(const rm_pass *p, uint32_t v);
/* Splits needles under 10° that the collapses left (their short edge joins two locked
 * vertices, or its collapse was refused) at a new vertex beside that edge (rm_insert.c),
 * within the room reserved; returns the insertions made. With last
 * (no relaxation follows), only where the split's thin halves can be flipped away at once.
 * *ok false when out of memory. */
size_t rm_insert_active(rm_pass *p, bool last, bool *ok);
/* Takes the mesh as found (the ntris triangles tri over the places pos, a copy the caller
 * keeps while the pass runs, the mesh as it is now) for centroid_bound (what flips, moves,
 * collapses and insertions keep to) and midpoint_low: measured now without a bound, where
 * flips and moves keep to them; under a bound, where only collapses, insertions and merges
 * onto a crease read them, when rm_collapse_bounds_need first asks (the same figures: the
 * found mesh does not change; torus and pretzel-genus2 never mend, and measuring every
 * centroid of the mesh was 6% of their pass). */
void rm_collapse_bounds(rm_pass *p, const double *pos, const uint32_t *tri, size_t ntris);
/* Measures centroid_bound and midpoint_low once (rm_collapse_bounds): each step that reads
 * them asks first. */
void rm_collapse_bounds_need(rm_pass *p);
/* True when distance d is at most midpoint_bound (what collapses and insertions keep to),
 * measured over the found mesh the first time midpoint_low does not decide: most passes
 * never mend, and most mendings never ask past midpoint_low (gyroid-ball: 141,000 midpoints
 * measured for the 76 collapses' checks). */
bool rm_midpoint_within(rm_pass *p, double d);

/* Drops the dead triangles and gone vertices from the mesh (which had nverts_before and
 * ntris_before when the pass began), keeps the vertices in order and orders the triangles by
 * origin (segments renumbered). With ren, ren gets the maps. False when out of memory (the
 * dead triangles are then collapsed ones, the gone vertices in no triangle). */
bool rm_compact(rm_mesh *r, size_t nverts_before, size_t ntris_before, ism_remesh_renumber *ren);

/* Marks the active vertices: those of triangles whose smallest angle is below
 * ISM_RM_COMFORT_DEG, and their neighbours; sets poorest and poor. Returns how many there are. Each
 * triangle's sine is measured again only when its shape changed since (sine). */
size_t rm_mark_active(rm_pass *p);

/* rm_pass.obtuse's mark of a triangle not measured since its shape changed. */
#define RM_OBTUSE_UNKNOWN 0xff

/* Triangle t changed its corners or their places (a move, flip, collapse or split): what
 * the pass remembers of its shape is gone. */
static inline void rm_shape_changed(rm_pass *p, uint32_t t)
{
    if (p->sine)
        p->sine[t] = NAN;
    if (p->obtuse)
        p->obtuse[t] = RM_OBTUSE_UNKNOWN;
}

/* Makes sine room for every triangle the pass may hold, taking over `found` (the caller's
 * measured sines of triangles 0 to from - 1, or NULL with from 0), those from `from` on not
 * measured yet (NAN). Out of memory it stays NULL (found freed) and rm_tri_sine measures
 * every time. */
static inline void rm_sine_open(rm_pass *p, double *found, size_t from)
{
    p->sine = realloc(found, (p->r.cap_tris ? p->r.cap_tris : 1) * sizeof *p->sine);
    if (!p->sine)
        free(found);
    for (size_t t = from; p->sine && t < p->r.cap_tris; t++)
        p->sine[t] = NAN;
}

/* Vertex v's position. */
static inline const double *rm_pos(const rm_pass *p, uint32_t v)
{
    return p->r.m->pos + 3 * (size_t)v;
}

/* ∇f vanishes at v: its normal was left zero (rm_pass.normal). */
static inline bool rm_normal_zero(const rm_pass *p, uint32_t v)
{
    const double *n = p->normal + 3 * (size_t)v;
    return n[0] == 0 && n[1] == 0 && n[2] == 0;
}

/* A triangle whose smallest angle's sine is below this is a needle to split (rm_insert.c)
 * and sizes the room for insertions (remesh.c). */
/* cos of the angle between normals n (length ln) and m (lm); -1 when either vanishes. */
static inline double rm_cos_bend(const double *n, double ln, const double *m, double lm)
{
    return ln > 0 && lm > 0 ? ism_dot3(n, m) / (ln * lm) : -1;
}
static inline double rm_insert_poor(void) { return sin(ISM_RM_INSERT_DEG * M_PI / 180); }

/* The sine of ISM_RM_COLLAPSE_DEG: a triangle whose smallest angle's sine is below it is poor
 * (the collapses' level). */
static inline double rm_collapse_poor(void) { return sin(ISM_RM_COLLAPSE_DEG * M_PI / 180); }

/* The sine of triangle t's smallest angle (rm_min_sine of its corners in order), measured
 * once while its shape holds (sine). */
static inline double rm_tri_sine(rm_pass *p, uint32_t t)
{
    double s = p->sine ? p->sine[t] : NAN;
    if (isnan(s)) {
        const uint32_t *v = p->r.m->tri + 3 * (size_t)t;
        const double *x = p->r.m->pos;
        s = rm_min_sine(x + 3 * (size_t)v[0], x + 3 * (size_t)v[1], x + 3 * (size_t)v[2]);
        if (p->sine)
            p->sine[t] = s;
    }
    return s;
}

/* Tries to move free vertex v toward its fan's centroid (rm_relax.c); true when it moved. */
bool rm_relax_vertex(rm_pass *p, uint32_t v);

/* Moving v to x puts no centroid of its fan farther from f = 0 than the mesh's farthest
 * before the pass or the fan's farthest now (bounded: every centroid and edge midpoint of
 * the fan within max_error, rm_bound.h). */
bool rm_centroids_stay(rm_pass *p, uint32_t v, const double *x);

/* One sweep over the free vertices whose fans face both sides of ∇f (pleats): each moves to
 * the mean of its neighbours in the tangent plane, back on f = 0, when fewer of its triangles
 * then face the minority side (rm_unfold.c); returns the moves made. */
size_t rm_unfold_sweep(rm_pass *p);

/* One sweep of tangential relaxation over the free active vertices whose mark is at most
 * most (UINT8_MAX: every active one); returns the moves made. */
size_t rm_relax_sweep(rm_pass *p, uint8_t most);

/* x lies between a and b along their chord, inside ISM_RM_SLIDE_KEEP_ORDER of either end
 * (rm_slide.c). */
bool rm_in_order(const double *x, const double *a, const double *b);

/* One sweep sliding the active box-boundary vertices (slide) along their boundary curve
 * toward the middle of their two boundary neighbours (rm_slide.c); returns the moves made. */
size_t rm_slide_sweep(rm_pass *p);

/* One sweep over the active vertices beside a min/max crease (rm_crease_slide.c): each is
 * merged with a crowding neighbour onto the crease, snapped onto it, or slid along it toward
 * the middle of its two neighbours on it, on both branches; returns the moves and merges
 * made (merges also count in collapses). */
size_t rm_crease_slide_sweep(rm_pass *p);

/* Locks the free vertices lying on a min/max crease of f's top (both branches within
 * rm_crease_slide.c's ISM_RM_CREASE_ON_REL of their mean edge: the polygoniser's own crease
 * points, crease_split.h), as a vertex the sweep moves onto it is locked: the relaxation
 * would move them off it (the cube minus a ball under its default bound: 408 vertices on the
 * crease before the pass, 32 after). Returns how many. */
size_t rm_crease_lock_on(rm_pass *p);

/* The fan of v: the sine of its smallest angle, mean edge length, the area-weighted centroid
 * and normal (the sum of the triangles' cross products: well defined even where a needle's
 * own normal is rounding noise). */
typedef struct rm_fan {
    double min_sine, mean_edge, centroid[3], normal[3];
} rm_fan;

void rm_fan_measure(const rm_pass *p, uint32_t v, rm_fan *f);
/* v's fan normal as rm_fan_measure has it: its triangles' unnormalised normals (rm_cross, in
 * corner order) summed in slot order; what the collapses test new triangles against
 * (rm_collapse.c's fan_before) reads the same bits. */
void rm_fan_normal(const rm_pass *p, uint32_t v, double normal[3]);

/* The (unnormalised) normal of v's i-th triangle (in its incidence slot) with v read at x;
 * returns its length (twice the area). */
double rm_fan_cross(const rm_pass *p, uint32_t v, uint32_t i, const double *x, double n[3]);

/* True when the triangle of corners t (vertex indices, read at their places now) would turn
 * over with normal n (unnormalised) once v (one of its corners, or none) has moved where ∇f's
 * unit normal is gv: it faces ∇f's side at a corner now and not then (the other corners'
 * normals as the pass keeps them). Where the surface bends faster than the cells (beside
 * Steiner's pinch points) a move or merge within the fan's limits can still turn it over. */
bool rm_turns_over(const rm_pass *p, const uint32_t *t, uint32_t v, const double gv[3],
                   const double n[3]);

/* True when moving v to x keeps every triangle of its fan facing within a limit of the fan's
 * normal, and leaves the fan's smallest angle no worse (or comfortable). */
bool rm_fan_accepts(const rm_pass *p, uint32_t v, const double x[3], const rm_fan *f);

/* Newton from x onto f = 0 (with axis >= 0: within the plane x[axis] = const, ∇f's component
 * along it dropped); g gets ∇f there. False when ∇f vanishes or it does not converge. */
bool rm_project(rm_pass *p, double x[3], double scale, int axis, double g[3]);

/* Puts v at x (on f = 0, ∇f there g): position, unit normal, the mesh's normal on its side. */
void rm_commit_move(rm_pass *p, uint32_t v, const double x[3], const double g[3]);

/* Distance estimate |f| / |∇f| at x (INFINITY where ∇f vanishes); bounded, plus the Newton
 * step's (rm_bound_distance), as every bound under max_error is measured. */
double rm_distance(rm_pass *p, const double x[3]);
/* The same at the midpoint of ab, and at the centroid of abc. */
double rm_midpoint_distance(rm_pass *p, const double *a, const double *b);
double rm_centroid_distance(rm_pass *p, const double *a, const double *b, const double *c);

#endif
