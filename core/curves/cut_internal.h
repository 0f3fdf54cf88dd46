/* cut_internal.h — what the cut's files share (not public): the state of cutting the mesh
 * along one function after another, and the small operations on it that the tangency
 * points (tangency.c) use too. */
#ifndef ISM_CUT_INTERNAL_H
#define ISM_CUT_INTERNAL_H

#include "core/curves/branches.h"
#include "core/curves/cut_cells.h"
#include "core/curves/cut_fn.h"
#include "core/curves/cut_types.h"
#include "core/mesh/mesh.h"
#include "core/singular/key_map.h"

#define CUT_NONE UINT32_MAX
/* First capacity of the growable arrays: a cut has hundreds of edges even for one plane
 * section at depth 6. */
#define CUT_FIRST 256

/* An edge with both ends on the curve: the signs of g seen across it (bit 1 +, bit 2 −) and
 * how many triangles have it. */
typedef struct cut_zero_edge {
    uint32_t a, b;
    uint8_t mask, seen;
} cut_zero_edge;

/* Per vertex, for the current function: how near the curve it is, and the tangency seeds'
 * counts (tangency.c). Zero between functions (reset through near_list). */
typedef struct cut_vscratch {
    double spread;       /* largest |g(w) − g(v)| to a neighbour */
    uint32_t fn;         /* the earlier curve it lies on + 1 (0: none seen) */
    uint32_t nbr[2];     /* its chain neighbours on that curve */
    uint8_t changes;     /* sign changes of g(w) − g(v) round it */
    uint8_t deg, up;     /* chain edges, and how many lead up */
} cut_vscratch;

typedef struct cut_state {
    ism_cut_eval *ev;
    ism_mesh *m;
    ism_cut *c;
    double tol;
    ism_key_map split;       /* edge key -> index into split_v */
    uint32_t *split_v;
    size_t cap_split;
    uint32_t *vcurve;        /* per vertex: the first function it lies on, CUT_NONE when none */
    size_t cap_vcurve;
    size_t cap_edges;
    double *gv;              /* g at the vertices of the current function */
    double *reach;           /* per vertex: its longest edge (how far Newton may move a point
                                of its edges: the polygoniser's vertices near a crease may lie
                                that far off the surface) */
    signed char *sg;
    size_t cap_gv;           /* room in gv, reach, sg and vs */
    cut_vscratch *vs;
    uint8_t *near;           /* per vertex: 1 a corner of a triangle the curve crosses or
                                touches, 2 a ring further, 0 farther */
    uint32_t *near_list;     /* the vertices with vs[v].near set */
    size_t n_near, cap_near;
    uint32_t *stars;         /* the triangles at the curve's corners (near 1: their stars) */
    size_t nstars, cap_stars;
    size_t slot;             /* the triangle being split (its first piece goes there), or
                                SIZE_MAX: pieces appended */
    uint32_t *parent;        /* per triangle: the input mesh's triangle it lies in */
    size_t cap_parent;
    uint32_t from;           /* the parent of the triangle being split (of appended pieces) */
    ism_key_map zero;        /* edge key -> index into zero_edge (the current function) */
    cut_zero_edge *zero_edge;
    size_t cap_zero;
    cut_cells cells;         /* where the current function's work is (cut_cells.h) */
    uint32_t *ehead;         /* per vertex: its first cut edge end (2 e + end), CUT_NONE */
    size_t cap_ehead;
    uint32_t *enext;         /* per cut edge end: the vertex's next one */
    size_t cap_enext;
    size_t fn;               /* the current function */
    size_t edits;            /* tangency edits of the mesh (moves, splits, merges) so far */
    ism_branches *branches;  /* f's branches, made when a crease is cut (crease.c), or NULL */
    ism_cut_resid *vres;     /* per vertex: the residuals where Newton put it (cut_resid.c;
                                nk 0 when none were kept) */
    size_t cap_vres;
} cut_state;

uint64_t cut_edge_key(uint32_t a, uint32_t b);
/* The slot of edge a-b in map, with *arr (elem bytes a slot) grown to hold it; *added when the
 * edge is new (its slot then holds nothing yet: the caller fills it). CUT_NONE when out of
 * memory. */
uint32_t cut_edge_slot(ism_key_map *map, uint32_t a, uint32_t b, void **arr, size_t *cap,
                       size_t elem, bool *added);

/* Appends triangle (a, b, c) as a piece of s->from (its parent). False when out of memory. */
bool cut_add_triangle(cut_state *s, uint32_t a, uint32_t b, uint32_t c);

/* A copy of the parents of the first nt triangles (NULL when out of memory). */
uint32_t *cut_parents_copy(const cut_state *s, size_t nt);

/* Notes that vertex v lies on curve fn (the first such curve is kept). */
bool cut_set_vcurve(cut_state *s, uint32_t v, uint32_t fn);
uint32_t cut_vcurve_of(const cut_state *s, uint32_t v);

/* The cut edge a-b (either way round; fn CUT_NONE: replaced) by a walk of a's list, or
 * CUT_NONE. (A hash of all cut edges, probed at random, cost a tenth of the benchmark's cut;
 * a vertex has a handful.) */
uint32_t cut_find_cut_edge(const cut_state *s, uint32_t a, uint32_t b);

/* Records edge a-b as lying on curve fn (once; listed at both ends: ehead / enext). */
bool cut_add_cut_edge(cut_state *s, uint32_t a, uint32_t b, uint32_t fn);

/* Replaces the cut edge a-b (on curve fn) by a-v and v-b. */
bool cut_split_cut_edge(cut_state *s, uint32_t a, uint32_t b, uint32_t v, uint32_t fn);

/* Sets the branches on the two sides of cut edge a-b (a crease edge). */
bool cut_set_branches(cut_state *s, uint32_t a, uint32_t b, const uint32_t br[2]);

/* Edge u-w's slot in the split map (*slot): *v its vertex when the edge is split already,
 * else NONE (the caller makes it and stores it in split_v[*slot]). False when out of
 * memory. */
bool cut_split_slot(cut_state *s, uint32_t u, uint32_t w, uint32_t *slot, uint32_t *v);

typedef double (*cut_sign_fn)(void *ctx, const double p[3]);

/* The sign change of fn on segment a-b (fn(a) = ga, fn(b) of the other sign) by bisection to
 * 2^-40 of the segment: a start for Newton where the function bends too much for the linear
 * estimate. */
void cut_bisect(cut_sign_fn fn, void *ctx, const double a[3], const double b[3], double ga,
                double p[3]);

/* The unit normal ∇f/|∇f| at p, oriented like ref (ref NULL: as ∇f points — at a crease
 * point, where the two sides' normals may be more than 90° apart, the neighbour's normal is
 * no guide to the sign). */
void cut_normal_at(cut_state *s, const double p[3], const float ref[3], float out[3]);

/* Emits triangle (l u w) split by a cut from p on l-u to q on l-w: (l p q) and the quad
 * (p u w q) by its shorter diagonal (winding kept). */
bool cut_emit_lone(cut_state *s, uint32_t l, uint32_t u, uint32_t w, uint32_t p, uint32_t q);

/* Per vertex: its longest edge into len (0 for a vertex no triangle uses). */
void cut_longest_edges(const ism_mesh *m, double *len);

/* Marks the vertices near the current curve (near, near_list) and their longest edges
 * (reach: of a vertex a ring further, among the triangles at the curve's corners: listed
 * in stars), and has g at all of them in gv and sg; the others' reach is left stale. False
 * when out of memory. */
bool cut_mark_near(cut_state *s);

/* Clears the per-vertex scratch of the near vertices. */
void cut_clear_near(cut_state *s);

/* Room in gv, reach and sg for the mesh's vertices. */
bool cut_grow_vertex_arrays(cut_state *s);

/* Difference step of the Hessians of silhouettes and creases, × the longest edge at the
 * point (tangency seeds, node branch directions). */
#define CUT_FD_STEP_REL 1e-4

/* Whether v lies on no curve but (maybe) k's own: moving it along k keeps the others. */
bool cut_on_no_other(const cut_state *s, uint32_t v, size_t k);

/* The triangles with a corner in the star of v (its 2-ring of triangles) into *out (grown;
 * free it). False when out of memory. */
bool cut_ring_triangles(const ism_mesh *m, uint32_t v, uint32_t **out, size_t *n);

/* The (unnormalised) normal of triangle tv, by its winding, with its corner `moved` taken
 * at p. */
void cut_tri_normal(const ism_mesh *m, const uint32_t *tv, uint32_t moved, const double *p,
                    double n[3]);

/* Whether u may move to p: its triangles among tris (but those with vertex skip; NONE for
 * none) keep their orientation, and (need_node) g_k's signs round it change at least four
 * times once u is on the curve. */
bool cut_can_move(cut_state *s, const uint32_t *tris, size_t nt, uint32_t u,
                  const double p[3], bool need_node, uint32_t skip);

/* Puts vertex u at p, on curve k (g_k taken as 0 there); tris (nt of them) hold u's
 * triangles. False when out of memory. */
bool cut_move_vertex(cut_state *s, size_t k, uint32_t u, const double p[3],
                     const uint32_t *tris, size_t nt);

/* Splits every triangle with edge a-b at the new vertex x (winding kept). */
bool cut_split_triangles_at(cut_state *s, uint32_t a, uint32_t b, uint32_t x);

/* Node u (a vertex on a node of curve k, where g_k = 0 touches the surface) made to meet
 * its four branches: each followed out of u's star, the link edges it crosses split at it
 * and link vertices it passes put on it (or merged into the vertex on the curve beside
 * them), so the cut leaves u four times whatever the star (node.c). reach: the longest
 * edge near u. False when out of memory. */
bool cut_node_branches(cut_state *s, size_t k, uint32_t u, double reach);

/* The grid of triangle cells (cut_cells.c). Build: from the whole mesh (cells.valid false
 * when there is nothing to index). Place: a triangle appended to the mesh. Grow: triangle
 * t's corners changed in place. Moved: a vertex moved to p, its triangles within r of it.
 * Ready: built when not valid or outgrown by the mesh.
 * Select: the triangles in the cells g_k = 0 may cross into cells.tris and those of the
 * ring round them into cells.ring_tris (both ascending; every triangle in cells.tris when
 * the grid is not valid), the vertices of cells.tris not yet seen for k into cells.verts,
 * with g_k at them in gv and sg. Each is a no-op while the grid is not valid; false when
 * out of memory. */
bool cut_cells_build(cut_state *s);
/* The grid built when it is not valid or the mesh has outgrown it. */
bool cut_cells_ready(cut_state *s);
void cut_cells_free(cut_cells *c);
bool cut_cells_place(cut_state *s, size_t t);
void cut_cells_grow(cut_state *s, size_t t);
void cut_cells_moved(cut_state *s, const double p[3], double r);
bool cut_cells_select(cut_state *s, size_t k);
/* g of the current function at the near vertices (cut_mark_near) where it is not known yet
 * (corners of the ring's triangles only: their signs are known, their values were not
 * needed before), into gv and sg. False when out of memory. */
bool cut_cells_near_values(cut_state *s);

/* The sign of the current function at vertex v (evaluated when v was not listed for it). */
signed char cut_sign_of(cut_state *s, uint32_t v);

/* Vertex v lies on the current curve: g taken as exactly 0 there. */
void cut_on_curve_now(cut_state *s, uint32_t v);

/* Keeps the residuals of the last Newton for vertex v when it ended where v is (the final
 * measure then needs no evaluation there). False when out of memory. */
bool cut_note_residuals(cut_state *s, uint32_t v);

/* The largest distances of the cut edges' ends to f = 0 and to their curves into
 * c->worst_f and c->worst_g: kept residuals where the vertex still is, else evaluated. */
void cut_measure_residuals(cut_state *s);

/* Finds where g_k = 0 touches the surface or an earlier curve (critical.h) and makes each
 * point a mesh vertex on which g_k is taken as exactly 0, so the cut meets there: a node of
 * degree 4 on the surface, a touching crossing on an earlier curve. Runs after g_k's signs
 * are known, before the triangles are split. False when out of memory. */
bool cut_tangencies(cut_state *s, size_t k);

/* Cuts the mesh along the creases of f (function k, of kind crease): each vertex labelled
 * with f's branch there, every mesh edge whose ends take branches A and B split at the
 * point of f_A = f_B = 0 on it, a triangle of three branches at the triple point
 * f_A = f_B = f_C = 0 (crease.c). False when out of memory. */
bool cut_crease(cut_state *s, size_t k);

#endif
