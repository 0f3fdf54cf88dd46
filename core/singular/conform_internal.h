/* conform_internal.h — what the files of the conformance pass share: the surgery context
 * (mesh, per-triangle dead marks, vertex→triangle incidence), hole loops, and the polyline
 * of a curve with its arclength parameter. Not a public header. */
#ifndef ISM_CONFORM_INTERNAL_H
#define ISM_CONFORM_INTERNAL_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/eval/eval.h"
#include "core/mesh/mesh.h"
#include "core/octree/edge_keys.h"
#include "core/singular/conform_stats.h"
#include "core/singular/key_map.h"
#include "core/singular/locus.h"

#define CF_NONE UINT32_MAX

/* Levels of the triangle grid (conform_grid.c): doubling cells from two finest cells, and
 * one last cell for triangles larger than all of them. */
#define CF_TGRID_LEVELS 26

/* The triangles of the mesh in a loose multi-level grid (conform_grid.c). The mesh's
 * triangles when the grid was made (the polygoniser's) are filed lazily, only those whose
 * box meets the region the queries have needed so far (`cover`); every triangle appended
 * after is filed at once. */
typedef struct cf_tgrid {
    double lo[3], side;     /* origin, level-0 cell side */
    ism_key_map cells;      /* packed (level, cell coordinates) → cell number */
    uint32_t *head;         /* per cell: the last triangle filed there (CF_NONE: none) */
    double *cell_box;       /* per cell: 6, a box holding every triangle filed there */
    uint32_t *next;         /* per triangle: the one filed before it in its cell */
    uint32_t *cell_of;      /* per triangle: its cell (CF_NONE: not filed yet) */
    uint32_t *stamp;        /* per triangle: the gather that last took it */
    uint32_t epoch;
    uint64_t last_key;      /* the cell the last triangle was filed in (consecutive ones of
                               the polygoniser's mesh mostly share it): no hash probe then */
    uint32_t last_cell;     /* ... its number, CF_NONE before the first */
    size_t cap_head, cap_next, cap_cell_of, cap_stamp, cap_cell_box;
    size_t ntris;           /* triangles known: 0 .. ntris-1 */
    size_t base;            /* triangles 0 .. base-1 are the mesh's at cf_tgrid_init */
    double cover[6];        /* every one of those whose box meets this box is filed */
    size_t cover_passes;    /* passes over them (cf_tgrid_cover's, counted as each starts,
                               whether or not it files anything) */
    int threads;            /* threads of those passes (1: the calling thread alone) */
    size_t per_level[CF_TGRID_LEVELS];
    uint64_t *occupied;     /* a bit per hash of a cell key, set as the cell is added: a
                               query skips the map's probe where its bit is clear */
    int occupied_shift;     /* 64 less log2 of occupied's bits (a power of two) */
} cf_tgrid;

/* A growable list of triangle numbers. */
typedef struct cf_tris {
    uint32_t *t;
    size_t n, cap;
} cf_tris;

typedef struct cf_ctx {
    const ism_tape *f;
    ism_eval_ws *ws;
    ism_mesh *m;
    uint8_t *dead;          /* per triangle: removed by surgery (compacted at the end) */
    size_t cap_dead;
    /* Triangles around each vertex, built once (cf_ctx_prepare) and kept current: the
     * triangles then present in CSR form, inc_tri[inc_start[v] .. inc_start[v+1]) for
     * v < inc_nverts, those appended since in a stack per vertex (x_head[v], x_next[node],
     * node 3 (t − inc_ntris) + corner). Dead triangles stay listed (cf_inc_next skips them). */
    uint32_t *inc_start;
    uint32_t *inc_tri;
    size_t inc_nverts, inc_ntris;
    uint32_t *x_head, *x_next;
    size_t cap_x_head, cap_x_next;
    bool indexed;           /* incidence and grid built */
    cf_tgrid grid;          /* the triangles by position */
    uint8_t *singular;      /* per vertex, CF_VERTEX_* bits: made by the pass where ∇f
                               vanishes (normal from the adjacent triangles at the end), or
                               pinned (never moved by the untangling); 0 for the rest */
    size_t cap_singular;
    /* Per-vertex memo of one query (a surgery's distances to its curves): memo_d[v],
     * memo_i[v] hold an answer where memo_gen[v] == gen (cf_memo_reset starts a new one). */
    double *memo_d;
    uint32_t *memo_i, *memo_gen;
    uint32_t gen;
    size_t cap_memo_d, cap_memo_i, cap_memo_gen;
    /* Stopping (cf_poll): the caller's cancel flag, deadline and work budget */
    const volatile int *cancel;
    double deadline_ms;
    size_t work_max;
    size_t since_poll;      /* work since the last clock read */
    bool stopped;           /* set once a poll found a reason to stop: every loop ends */
    double origin[3], extent; /* the box's low corner and longest side */
    double cell;            /* finest octree cell: the scale of the surgery */
    int threads;            /* the grid's passes over the mesh run on this many */
    struct cf_grade *grade; /* the rows graded toward the curve of the loop being zipped
                               (conform_grade.c), NULL: zipped straight to the curve */
    ism_conform_stats *st;
} cf_ctx;

/* Radius of the ball or tube cut around the locus, in finest cells: the polygoniser's
 * confusion (digon loops, island caps in a neighbour cell, polygons crossing without a shared
 * edge) stays in the cells that hold the singularity and their neighbours, within about
 * 2√3 cells; a triangle is cut when any part of it comes this close. */
#define CF_RHO_CELLS 2.5
/* ... and at least this many times the longest edge of the triangles there, where the
 * octree did not reach its finest depth. */
#define CF_RHO_EDGES 1.25

/* The rim of a cut must lie where no other sheet comes within this many cells along its
 * normals (two spheres touching stay closer than a cell out to about √(cell × radius));
 * until then the cut grows by CF_GROW, at most CF_MAX_GROW times (cf_cut_clean). */
#define CF_CLEAR_CELLS 1.5
#define CF_GROW 1.4
#define CF_MAX_GROW 6

/* One run of the pass: the context, the locus and the mesh vertex given to each point. */
typedef struct cf_run {
    cf_ctx c;
    ism_locus *l;
    const ism_locus_options *o;
    uint32_t *point_vertex; /* per locus point: its mesh vertex, or CF_NONE */
} cf_run;

/* A chain of hole-boundary vertices, oriented so that new triangles traverse v[i] → v[i+1]
 * (opposite to the kept triangle on that edge). closed: v[n-1] → v[0] is an edge too. */
typedef struct cf_loop {
    uint32_t *v;
    size_t n;
    bool closed;
} cf_loop;

typedef struct cf_loops {
    cf_loop *l;
    size_t n, cap;
} cf_loops;

void cf_loops_free(cf_loops *ls);

/* Entries of a polyline grid cell whose segments share one box (cf_polyline.g_blk): a cell
 * holds runs of consecutive segments of its curve (Klein bottle at E 0.00327: about 24), and a
 * run of 8 spans a few tube radii, so a query within a radius or two of the curve reads one
 * or two blocks of a cell and skips the rest by one box test each. */
#define CF_SEG_BLOCK 8

/* A curve's polyline with cumulative arclength s[i] at point i (s[n] = total length when
 * closed: the closing segment), and a uniform grid over its segments for nearest-point
 * queries. */
typedef struct cf_polyline {
    const double *p;        /* 3 per point */
    size_t n;
    bool closed;
    double *s;              /* n + 1 entries */
    double length;
    double lo[3], hi[3];    /* the points' bounding box (lo: also the grid's origin) */
    double step;            /* grid cell side */
    int dim[3];
    uint32_t *g_start, *g_seg; /* segments per grid cell (CSR) */
    double (*g_box)[6];     /* at g_start[c]: the box of cell c's segments clipped to the
                               cell (grown by the rounding slack): lo xyz, hi xyz */
    double (*ball)[4];      /* per segment: its midpoint and half its length (grown by
                               its rounding) */
    double (*line)[8];      /* per segment: its midpoint, half its length, unit direction
                               and its largest coordinate's magnitude (conform_curve.c's
                               estimates: no rounding grown into them) */
    double (*g_blk)[6];     /* at g_start[c] + CF_SEG_BLOCK b: the box of the segments
                               filed there from that entry on, CF_SEG_BLOCK at most (the
                               distance alone skips a block whose box is beyond its bound) */
    bool pinch[2];          /* its first / last point is a pinch point (set by the caller
                               after cf_polyline_init; open curves only) */
} cf_polyline;

/* ---- conform_mesh.c: incidence, dead marks, growth ---- */
/* Makes room for need elements of size sz in *v (capacity *cap, doubling), the new room
 * zeroed. False when out of memory (*v unchanged). Inline where the room is there already:
 * the pass asks before every triangle and vertex it appends (215k calls on crossing-spheres,
 * 7.8M instructions as calls, callgrind); cf_grow_room grows. */
bool cf_grow_room(void **v, size_t *cap, size_t need, size_t sz);
static inline bool cf_grow(void **v, size_t *cap, size_t need, size_t sz)
{
    return need <= *cap || cf_grow_room(v, cap, need, sz);
}
/* Sorts n keys increasing (a radix sort: qsort's result at a fraction of its cost). */
void cf_sort_u32(uint32_t *a, size_t n);
/* Builds the incidence and the grid on first use (later calls only check room): O(T) once
 * per pass, both then kept current by cf_add_triangle and cf_undo. */
bool cf_ctx_prepare(cf_ctx *c);
void cf_ctx_free(cf_ctx *c);
bool cf_add_triangle(cf_ctx *c, uint32_t a, uint32_t b, uint32_t d);
/* cf_ctx.singular's bits: SINGULAR, a vertex with no normal (also set where ∇f gives none);
 * PINNED, a vertex (made by the pass) that stays where it is: the untangling
 * (conform_refine.c) moves no such vertex. */
#define CF_VERTEX_SINGULAR 1
#define CF_VERTEX_PINNED 2
/* A vertex at p with those bits (false / true: 0 / CF_VERTEX_SINGULAR). */
uint32_t cf_add_vertex(cf_ctx *c, const double p[3], uint8_t flags);
/* ∇f where cf_project_keep left its point (at false: it evaluated none there). */
typedef struct cf_grad {
    double g[3];
    bool at;
} cf_grad;
/* cf_add_vertex, its normal from kept->g when kept->at (the same evaluation: the same
 * normal); the pass projects every ring vertex it adds (5.7k gradients on crossing-spheres'
 * refill, evaluated twice before). */
uint32_t cf_add_vertex_kept(cf_ctx *c, const double p[3], uint8_t flags, const cf_grad *kept);
/* Drops the triangles from ntris and the vertices from nverts on (appended by a surgery
 * that failed) from the mesh, its incidence and its grid. */
void cf_truncate(cf_ctx *c, size_t ntris, size_t nverts);
/* The live triangles at vertex v, one by one: cf_inc_begin, then cf_inc_next until false. */
typedef struct cf_inc {
    uint32_t i, end, node;
} cf_inc;
void cf_inc_begin(const cf_ctx *c, uint32_t v, cf_inc *it);
bool cf_inc_next(const cf_ctx *c, cf_inc *it, uint32_t *t);
/* Counts the live triangles on the edge (a, b); the first cap of them into out. Inline: the
 * hole's rim asks it for every edge of every removed triangle (450k calls on Steiner d3:10, a
 * call of its own cost ism_conform_mesh 2.6% more, callgrind). */
static inline size_t cf_live_on_edge(const cf_ctx *c, uint32_t a, uint32_t b, uint32_t *out,
                                     size_t cap)
{
    cf_inc it;
    uint32_t t;
    size_t n = 0;
    for (cf_inc_begin(c, a, &it); cf_inc_next(c, &it, &t);) {
        const uint32_t *v = c->m->tri + 3 * (size_t)t;
        if (v[0] == b || v[1] == b || v[2] == b) {
            if (n < cap)
                out[n] = t;
            n++;
        }
    }
    return n;
}
/* Vertex v's normal from ∇f at its place (as cf_add_vertex sets it; 0 where |∇f| is 0 or not
 * finite). */
void cf_set_normal(cf_ctx *c, uint32_t v);
/* Counts `work` units done and returns c->stopped: set when the cancel flag is up, the
 * deadline has passed (read every ISM_CONFORM_POLL_WORK units) or the budget is spent. Loops
 * whose length grows with the mesh call it per element and end when it returns true; a
 * surgery that sees c->stopped is undone. Inline but for the clock (cf_poll_clock): it runs
 * once per element of those loops. */
bool cf_poll_clock(cf_ctx *c);
static inline bool cf_poll(cf_ctx *c, size_t work)
{
    if (c->stopped)
        return true;
    c->st->work += work;
    c->since_poll += work;
    if (c->work_max && c->st->work > c->work_max)
        c->stopped = true;
    if (c->since_poll >= ISM_CONFORM_POLL_WORK)
        return cf_poll_clock(c);
    return c->stopped;
}
/* Forgets the memo (O(1)) and makes room for every vertex. False when out of memory. */
bool cf_memo_reset(cf_ctx *c);
/* Squared length of the longest edge of triangle t. */
double cf_triangle_longest_edge2(const ism_mesh *m, uint32_t t);
/* Longest edge of the live triangles at vertex v / with a vertex within r of p (false when
 * out of memory). */
double cf_vertex_longest_edge(const cf_ctx *c, uint32_t v);
bool cf_longest_edge_near(cf_ctx *c, const double p[3], double r, double *out);
/* Removes dead triangles and the vertices only they used; recomputes the singular vertices'
 * normals. */
bool cf_compact(cf_ctx *c);

/* ---- conform_grid.c: the triangles by position ---- */
/* A widening reaches at least this share of the covered box's largest side beyond the box
 * asked for: each pass costs a look at every vertex and triangle, and a locus spread over the
 * mesh widened the box by one small query at a time (Barth's sextic at E 0.0259 before the
 * growth: 30 singular points, 28 passes, 38M of its 1,444M instructions). Each pass then
 * files what it reaches, and which triangles a query gathers does not change, only the order
 * they were filed in: the cutter's queries sort what they gather, the longest edge is a
 * maximum; the pinch untangling's list (conform_refine.c) keeps the gather order, which can
 * change only at a pass that CF_COVER_PLAIN_PASSES passes came before (mesh_identity's 217 runs
 * identical even growing from the first pass). */
#define CF_COVER_GROWTH 0.5
/* ... from this many passes on: a locus of a few parts (cross-cap's two pinch points and its
 * double line) is covered in a few passes, and a grown box would file triangles no query
 * needs (cross-cap at the default bound, ism_conform_mesh's instructions: 26.8M without the
 * growth, 29.4M growing from the first pass, 29.2M from the 4th, 26.8M from the 8th; Barth
 * at E 0.0259: 99M, 74.5M, 77M, 80.7M). */
#define CF_COVER_PLAIN_PASSES 8

/* An empty grid for a box with low corner origin and longest side extent, finest cells of
 * finest_cell, over the ntris triangles of the mesh (filed on demand, cf_tgrid_cover).
 * False on a degenerate scale or when out of memory. */
bool cf_tgrid_init(cf_tgrid *g, const double origin[3], double extent, double finest_cell,
                   size_t ntris);
void cf_tgrid_free(cf_tgrid *g);
/* Files triangle t of m, appended to the mesh since the grid was made (t = the number known
 * so far). False when out of memory. */
bool cf_tgrid_add(cf_tgrid *g, const ism_mesh *m, uint32_t t);
/* Makes sure every triangle whose box meets the box [lo, hi] is filed: when that box is not
 * covered yet, one pass over the mesh's first `base` triangles files those meeting it grown
 * by `ahead` on every side (room for the next widenings of a cut), and once
 * CF_COVER_PLAIN_PASSES passes came before, by at least CF_COVER_GROWTH times the covered box's
 * largest side. cf_tgrid_gather covers its query box itself (ahead 0, so grown only by
 * that); a caller that knows the region its next queries need asks for it first (a query not
 * covered costs a pass of its own). False when out of memory. */
bool cf_tgrid_cover(cf_tgrid *g, const ism_mesh *m, const double lo[3], const double hi[3],
                    double ahead);
/* Forgets the triangles from ntris on (filed last, forgotten first). */
void cf_tgrid_truncate(cf_tgrid *g, size_t ntris);
/* Starts a gather: the triangles taken by the cf_tgrid_gather calls that follow are
 * appended to their list once each. */
void cf_tgrid_begin(cf_tgrid *g);
/* Appends to out every triangle of m not dead whose bounding box meets the box [lo, hi]
 * and was not taken since cf_tgrid_begin. False when out of memory. */
bool cf_tgrid_gather(cf_tgrid *g, const ism_mesh *m, const double lo[3], const double hi[3],
                     const uint8_t *dead, cf_tris *out);
bool cf_tris_push(cf_tris *out, uint32_t t);
/* Query boxes are grown by this fraction of their scale (radius plus the coordinates'
 * magnitude): the tests they prefilter compare distances computed in floating point, a few
 * ulps off, and must never lose a triangle at exactly the radius. */
#define CF_QUERY_SLACK 1e-9

/* min and max by comparison: libm's fmin/fmax are calls, and these run once per triangle
 * box, grid cell and segment of the pass's queries. For finite operands the same as fmin /
 * fmax (-0 and +0 compare equal: either gives the same boxes, distances and answers); with
 * a NaN in b, a is returned, as fmin/fmax return the number when a is one. */
static inline double cf_min2(double a, double b)
{
    return b < a ? b : a;
}

static inline double cf_max2(double a, double b)
{
    return b > a ? b : a;
}

/* floor(u) clamped to [0, n − 1], 0 for a NaN, without libm's floor call (the grids ask it per
 * axis of every triangle filed and every query): u is clamped first, so truncation is floor. */
static inline int64_t cf_floor_clamped(double u, int64_t n)
{
    return !(u >= 0) ? 0 : u >= (double)n ? n - 1 : (int64_t)u;
}
/* The box around the segment ab (a point when a = b) grown by r and the slack. */
void cf_query_box(const double a[3], const double b[3], double r, double lo[3], double hi[3]);

/* ---- conform_hole.c: removal and hole loops ---- */
/* What a cut removes: the live triangles near() accepts. gather() appends to its list
 * (cf_tgrid_gather after cf_tgrid_begin) a superset of them: never one near() would accept
 * left out, each once. False from gather when out of memory. */
typedef bool (*cf_tri_pred)(const cf_ctx *c, uint32_t t, void *arg);
typedef struct cf_cutter {
    cf_tri_pred near;
    bool (*gather)(cf_ctx *c, void *arg, cf_tris *out);
    void *arg;
} cf_cutter;
/* Marks dead the triangles the cutter selects and the kept pieces of a few triangles they
 * enclose (*removed, in increasing order), chains the hole's boundary edges (edges left with
 * one live triangle that lost at least one) into loops, and grows the cut (*radius, which
 * the cutter reads through its arg, times a factor; a cutter must select at a larger radius
 * every triangle it selected at a smaller one) until the rim is clear of other sheets
 * (cf_rim_clear), a bounded number of times and never beyond max_radius. Returns false on
 * allocation failure (nothing marked then); stopped (c->stopped), it marks nothing and
 * returns no loop. */
bool cf_cut_clean(cf_ctx *c, const cf_cutter *cut, double *radius, double max_radius,
                  cf_loops *ls, uint32_t **removed, size_t *nremoved);
/* Undoes a cut whose refilling failed: revives the triangles, drops everything appended
 * since (ntris, nverts). */
void cf_undo(cf_ctx *c, const uint32_t *removed, size_t nremoved, size_t ntris, size_t nverts);
/* True when no rim vertex has another sheet of f = 0 within `clearance` along its normal:
 * the rim lies where the polygoniser's sheets are apart, outside its confusion. */
bool cf_rim_clear(cf_ctx *c, const cf_loops *ls, double clearance);
/* Squared distance from q to the triangle abc. */
double cf_point_triangle_d2(const double q[3], const double a[3], const double b[3],
                            const double c[3]);

/* ---- conform_fill.c: rings, ladders, fans ---- */
/* Moves p onto f = 0 by Newton along ∇f, unless that moves it more than max_move or does not
 * bring it closer (then p is kept). Returns |f| / |∇f| at p where it ends (INFINITY where ∇f
 * vanishes). */
double cf_project(cf_ctx *c, double p[3], double max_move);
/* cf_project, ∇f at the point it leaves in p into *kept (cf_add_vertex_kept). */
double cf_project_keep(cf_ctx *c, double p[3], double max_move, cf_grad *kept);
/* |f| / |∇f| at p (INFINITY where ∇f vanishes); ∇f into g, f into *fv. Inline: the
 * refill's untangling asks it for every triangle round every vertex it tries to move. */
static inline double cf_distance_estimate(cf_ctx *c, const double p[3], double g[3], double *fv)
{
    *fv = ism_eval_gradient(c->f, c->ws, p[0], p[1], p[2], g);
    double gl = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    return gl > 0 ? fabs(*fv) / gl : INFINITY;
}
/* Number of intermediate rings for a strip of width `width` next to a loop of mean edge
 * length `edge`. */
int cf_ring_count(double width, double edge);
double cf_loop_mean_edge(const cf_ctx *c, const cf_loop *l);
/* Triangles between two rows of equal length (a outer, b inner, same direction). */
bool cf_ladder(cf_ctx *c, const uint32_t *a, const uint32_t *b, size_t n, bool closed);
/* Fans the loop to vertex apex through `rings` rings of vertices between the loop and
 * apex_pos, projected onto f = 0. */
bool cf_fan(cf_ctx *c, const cf_loop *l, uint32_t apex, const double apex_pos[3], int rings);
/* Fans a loop to its centroid projected onto f = 0 (the fallback that leaves no crack). */
bool cf_fan_centroid(cf_ctx *c, const cf_loop *l);

/* ---- conform_curve.c: polylines ---- */
bool cf_polyline_init(cf_polyline *pl, const double *p, size_t n, bool closed, double step);
void cf_polyline_free(cf_polyline *pl);
/* Distance from q to the polyline, its arclength parameter and foot point (when not NULL);
 * returns INFINITY when nothing lies within `within` (the grid is searched that far). */
double cf_polyline_nearest(const cf_polyline *pl, const double q[3], double within, double *s,
                           double foot[3]);

/* Distance from q to the polyline's bounding box: a lower bound of cf_polyline_nearest's. */
double cf_polyline_box_distance(const cf_polyline *pl, const double q[3]);

/* ---- conform_angle.c: how far the sheets crossing along a curve stay close ---- */
/* The radius a tube around the npl polylines needs for its rim to be clear of the other
 * sheet (CF_CLEAR_CELLS along the normals), from the angle the two sheets cross at along
 * them (the median over sampled points; 0 where none is a transversal crossing). */
double cf_crossing_radius(cf_ctx *c, const cf_polyline *pl, size_t npl);

/* ---- conform_pinch.c: the rim beside a pinch point ---- */
/* Rim vertices whose feet lie this many tube radii (arclength) or less from a pinch end of
 * their curve are read in the umbrella's chart there: the cap round the end, where the feet
 * stop telling the way the rim runs (one radius), and as much again for the windows the ears
 * read their direction over on either side. */
#define CF_PINCH_REACH_RHO 2.0
/* The umbrella's chart at a pinch point: the point, the curve's unit tangent there (into the
 * curve), the direction the two sheets lie apart in (n) and the fold's (e = c × n). */
typedef struct cf_pinch {
    double p[3], c[3], n[3], e[3];
    int end;                /* the curve's end it is at: 0 first point, 1 last */
    bool on;
} cf_pinch;
/* The charts of the pinch ends of the npl polylines: out[2 k + e] for end e of pl[k] (on
 * false where it is no pinch point), the tangent read over the tube radius rho. */
void cf_pinch_ends(cf_ctx *c, const cf_polyline *pl, size_t npl, double rho, cf_pinch *out);
/* The chart of a pinch end of pl[k] within `reach` (arclength) of the foot parameter s, or
 * NULL. */
const cf_pinch *cf_pinch_near(const cf_pinch *ends, const cf_polyline *pl, int k, double s,
                              double reach);
/* The curve parameter of q's height along the chart's tangent (within the curve pl). */
double cf_pinch_param(const cf_pinch *ch, const cf_polyline *pl, const double q[3]);
/* The ring point at fraction t from rim vertex q's foot on the tangent line to q, moved onto
 * f = 0 along the tangent (cf_project's move where that finds no root near). */
void cf_pinch_ring_point(cf_ctx *c, const cf_pinch *ch, const double q[3], double t,
                         double out[3]);
/* The runs of loop l whose vertices' feet (curve cid[i], parameter u[i]) lie within reach of
 * one pinch end lose their steps backwards in the chart's sheet parameter (cf_clip_ears on
 * the run); l->v, u, foot and cid are compacted in place. Returns the ears clipped, -1 when
 * out of memory. */
int cf_pinch_ears(cf_ctx *c, const cf_pinch *ends, const cf_polyline *pl, cf_loop *l,
                  double *u, double *foot, int *cid, double reach, double rho);
/* The rim points the rings of loop l are scaled from (q: 3 per vertex): each vertex's
 * position, but the nearer end's of a rim edge that crosses the fold of the pinch chart
 * ch[i] of both its ends (NULL: none) is the edge's point on the fold, on_fold[i] then true
 * (conform_pinch.c). False when out of memory. */
bool cf_pinch_rim_points(cf_ctx *c, const cf_loop *l, const cf_pinch *const *ch, double *q,
                         bool *on_fold);

/* ---- conform_zip.c: zipping loops to a curve ---- */
/* Refills the hole loops cut around a group of npl double curves (meeting at shared end
 * points): each loop (through rings) is stitched to the vertices cv[k] (one per polyline
 * point) of the curves it runs along, by arclength. */
bool cf_zip_loops(cf_ctx *c, const cf_polyline *pl, const uint32_t *const *cv, size_t npl,
                  const cf_loops *ls, double rho);

/* ---- conform_grade.c: rows graded between a zip's row and its curve ---- */
/* Rows at most (a row 2^(K + 1) times as coarse as the curve gets K: 128 times, past the
 * planes' 98 curve edges under one row edge in the irrational box). */
#define CF_GRADE_MAX_ROWS 6
/* A side of a strip: row vertex r above curve vertex c, and the rows' vertices between. */
typedef struct cf_grade_side {
    uint32_t r, c, v[CF_GRADE_MAX_ROWS + 1]; /* v[1 .. rows] */
} cf_grade_side;
/* One loop's grading: its rows, where they lie and the sides made so far (shared by the
 * loop's stretches). refused: a stretch could not be graded (the caller zips the loop again
 * without). */
typedef struct cf_grade {
    int rows;
    double t[CF_GRADE_MAX_ROWS + 2]; /* row k at t[k] of the way from the curve to the row */
    cf_grade_side *side;
    size_t nside, cap;
    bool refused;
} cf_grade;
/* Rows to grade a row of mean edge row_edge, width from the curve, down to a curve of
 * curve_edge (0: none). */
int cf_grade_rows(double row_edge, double curve_edge, double width);
void cf_grade_init(cf_grade *g, int rows);
void cf_grade_free(cf_grade *g);
/* Fills the strip between row top[0 .. nt) (its parameters tx, non-decreasing) and the curve
 * vertices bot[0 .. nb) (bx, increasing) with g's rows: 1 done, 0 out of memory, -1 it cannot
 * (a stretch of no length). */
int cf_grade_strip(cf_ctx *c, cf_grade *g, const uint32_t *top, const double *tx, size_t nt,
                   const uint32_t *bot, const double *bx, size_t nb);

/* ---- conform_ears.c: a rim loop's backward steps clipped ---- */
/* Loop l along the curves pl (cid[i] the curve of vertex i, NULL: all on pl[0]; u[i] its
 * foot's arclength on it, foot[3 i] the foot; wind != 0: a closed loop winding that many
 * times round the closed curve pl[0]) loses the outer ends of its steps backwards along its
 * curve: each such vertex's ear (prev, v, next) becomes a triangle where it turns like the
 * hole and its new edge steps forwards. The way forwards is the winding's, else read from
 * the loop's steps nearby along one curve (nothing clipped where they disagree or barely move:
 * round the end of an open curve, at a junction of curves). The steps nearby must travel
 * the loop's mean edge; unit > 0 (a chart whose steps are a fraction of the edges): where
 * they do not, a way read against unit instead is taken, for steps backwards only. l->v, u,
 * foot and cid are compacted in place (l->n lowered). Returns the ears clipped, -1 when out
 * of memory. */
int cf_clip_ears(cf_ctx *c, const cf_polyline *pl, cf_loop *l, double *u, double *foot,
                 int *cid, int wind, double unit);
/* Cuts the spikes of the closed loops of ls: a kept triangle holding a loop vertex's both rim
 * edges, the vertex's only live triangle, is marked dead (added to the sorted *rm) and the
 * vertex leaves its loop. False when out of memory (nothing more marked dead; the caller
 * undoes the cut). */
bool cf_drop_spikes(cf_ctx *c, cf_loops *ls, uint32_t **rm, size_t *nrm);

/* ---- conform_refine.c: a round's edges, numbered ---- */
/* The edges (a, b) of a refinement round, numbered 0, 1, ... as first added (either way
 * round): open addressing with linear probing in a power-of-two table sized at the round's
 * start for max edges, at most half full (nothing grows or rehashes while a round runs). */
typedef struct cf_edge_slot {
    uint64_t key;   /* ism_edge_key of the edge */
    uint32_t index; /* its number; ISM_KEY_NONE: an empty slot */
} cf_edge_slot;

typedef struct cf_edge_table {
    cf_edge_slot *slot;
    int shift;         /* 64 less log2 of the slots */
    size_t n, max;     /* edges added; room for */
    size_t cap_slot;
} cf_edge_table;

/* Empties t with room for max edges (at most ISM_KEY_NONE), every slot empty and more slots
 * than room (twice); false when out of memory (room for none then). */
bool cf_edge_table_start(cf_edge_table *t, size_t max);
void cf_edge_table_free(cf_edge_table *t);

/* The number of edge (a, b), added when new (*added); ISM_KEY_NONE when max are held. */
static inline uint32_t cf_edge_table_add(cf_edge_table *t, uint32_t a, uint32_t b, bool *added)
{
    *added = false;
    if (t->max == 0)
        return ISM_KEY_NONE;
    uint64_t key = ism_edge_key(a, b);
    size_t mask = ((size_t)1 << (64 - t->shift)) - 1;
    /* Fibonacci hashing: the top bits of the key times 2^64 / φ */
    size_t j = (size_t)((key * 0x9e3779b97f4a7c15ull) >> t->shift);
    for (; t->slot[j].index != ISM_KEY_NONE; j = (j + 1) & mask)
        if (t->slot[j].key == key)
            return t->slot[j].index;
    if (t->n == t->max)
        return ISM_KEY_NONE;
    t->slot[j] = (cf_edge_slot){key, (uint32_t)t->n};
    *added = true;
    return (uint32_t)t->n++;
}

/* ---- conform_refine.c: the refill's triangles checked ---- */
/* The live triangles from nt0 on (made by the pass): those with a centroid or edge midpoint
 * farther than max_error from f = 0 have their longest edge off the locus halved (no half
 * shorter than min_edge; max_error 0: a quarter of the finest cell, halves of half a cell at
 * least); then those facing against ∇f, and the polygoniser's near the pinch points of l
 * (ISM_SING_PINCH), are untangled, their vertices not on the locus nor on a boundary
 * moved to their neighbours' mean, onto f = 0 (no centroid round them left farther than a
 * share of a cell, or max_error). False only when out of memory. */
bool cf_refine_refill(cf_ctx *c, size_t nt0, double max_error, double min_edge,
                      const ism_locus *l);

/* ---- conform_point.c, conform_tube.c: the two surgeries ---- */
/* Point i of the locus made one vertex shared by its cones. False only when out of memory
 * (the mesh is then as before). */
bool cf_conform_point(cf_run *r, size_t i);
/* The double curves idx[0..n) (a group meeting at shared end points) made chains of mesh
 * edges. False only when out of memory (the mesh is then as before). */
bool cf_conform_curves(cf_run *r, const size_t *idx, size_t n);

/* Whether q lies farther than r from every curve of a tube, by the corners of a triangle:
 * vd[k] is corner k's distance to the nearest curve (not finite: nothing within r + reach,
 * or outside the curves' box grown by that, so r + reach is a lower bound), and a curve
 * point is at least vd[k] − |q − corner k| from q (the triangle inequality). The bound must
 * exceed r by more than the rounding of the distances (CF_QUERY_SLACK). tri_in_tube asks no
 * polyline query of such a point: none could answer within r. */
bool cf_far_by_corners(const double q[3], const double *const corner[3], const double vd[3],
                       double r, double reach);

/* The tube's selection alone (conform_tube.c), as its tests ask it. A tube of radius r round
 * the npl polylines pl, judging edges up to reach long by their corners' distances (NULL
 * when out of memory); its radius set as the cut's widening sets it, the memo's distances
 * kept from the first radius on (false when out of memory); whether it takes triangle t of
 * c's mesh (some point of it within r of a curve). */
typedef struct cf_tube cf_tube;
cf_tube *cf_tube_new(const cf_polyline *pl, size_t npl, double r, double reach);
bool cf_tube_radius(cf_ctx *c, cf_tube *tb, double r);
bool cf_tube_selects(const cf_ctx *c, cf_tube *tb, uint32_t t);
void cf_tube_free(cf_tube *tb);

/* ---- conform_kept.c: curves the polygoniser's mesh already follows ---- */
/* True when the live mesh holds each of the n open polylines pl (of curves cu, no end at a
 * pinch point) as a chain of edges from its first point to its last, each edge with two
 * sheets' triangles and no other non-manifold edge at the chain (conform_kept.c); the
 * chains' vertices are then marked CF_VERTEX_SINGULAR and the curves' end points given
 * their end vertices (r->point_vertex). False (nothing changed) otherwise, also when out of
 * memory or stopped. */
bool cf_curves_kept(cf_run *r, const cf_polyline *pl, const ism_sing_curve *const *cu, size_t n);

#endif
