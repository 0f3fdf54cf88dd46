/* locus.h — the singular locus of f = 0 inside a box, found from f itself (never from a mesh):
 * certified singular points, traced singular curves (double curves, whiskers) and double
 * sheets (zero sets where f does not change sign). These are the types the stages of
 * core/singular/ share:
 *
 *     search.c   interval subdivision of the box: cells where F and ∇F may both hold 0
 *        │       ─▶ candidate boxes, each with the rank of the Hessian at its centre's
 *        │          projection onto ∇f = 0
 *     points.c   rank-3 (and isolated) clusters ─▶ Newton on ∇f, Krawczyk certificate,
 *        │       type from the Hessian's eigenvalues
 *     curves.c   rank-2 boxes ─▶ predictor–corrector polylines on f = ∇f = 0, ends typed
 *        │       (pinch, triple point, box exit) or closed
 *     sheets.c   rank-1 boxes ─▶ a mesh of the double sheet
 *        ▼
 *     conform.c  the polygoniser's mesh is made to conform: a node is one vertex shared by
 *                its cones, a double curve a chain of mesh edges
 *
 * Sizes and tolerances are relative to the box diagonal unless a field says otherwise. */
#ifndef ISM_LOCUS_H
#define ISM_LOCUS_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>

/* What a singular point is, from the Hessian H of f there (eigenvalues λ1 ≤ λ2 ≤ λ3). */
enum ism_sing_type {
    ISM_SING_NODE = 0,       /* H non-degenerate, indefinite: a real cone of two nappes */
    ISM_SING_ISOLATED = 1,   /* H definite: f = 0 only at the point */
    ISM_SING_CUSP = 2,       /* H of rank 2 at an isolated zero of ∇f (x² + z² − y³) */
    ISM_SING_DEGENERATE = 3, /* isolated, H of rank ≤ 1 (two spheres touching), or rank 2
                                not recognised as a cusp */
    ISM_SING_PINCH = 4,      /* a double curve turns into a whisker (Whitney umbrella) */
    ISM_SING_TRIPLE = 5,     /* three or more branches of singular curves meet */
    ISM_SING_TYPES
};

/* How a point's enclosure was proved (points.h, point_cert.h). */
enum ism_cert_kind {
    ISM_CERT_NONE = 0,
    ISM_CERT_KRAWCZYK = 1,  /* one zero of ∇f in the box (non-singular Hessian) */
    ISM_CERT_DEFLATION = 2, /* rank-2 point: one zero of the deflated system in the box — a
                               point where H is singular and ∇f = ε n, |ε| ≤ perturbation
                               (core/singular/deflate.h) */
    /* The type's defining system (core/singular/typecert.h) has one regular solution x*
     * in the box: no other point of the box is of that type, and x* is of that type for f
     * changed by at most `perturbation` (the system's relative residual at x*). */
    ISM_CERT_RANK0 = 3,     /* ∇f = 0, H = 0 (triple points) */
    ISM_CERT_RANK1 = 4,     /* ∇f = 0, rank H = 1 (pinch points) */
    ISM_CERT_A3 = 5,        /* ∇f = 0, Hv = 0, D³f[v, v, v] = 0 (an A3 point) */
    ISM_CERT_KINDS
};

/* Why a point is not certified. */
enum ism_uncert_why {
    ISM_UNCERT_NONE = 0,      /* certified */
    ISM_UNCERT_CONTACT = 1,   /* Hessian rank 1 and the rank-1 system singular: two sheets
                                 touching (touching spheres). No regular defining system
                                 exists, and double precision places such a point only to
                                 ~(1e-16)^(1/3) of f's scale: not certifiable in principle */
    ISM_UNCERT_CUBIC = 2,     /* rank 2, cubic and quartic terms along the null direction 0
                                 (A4 or worse): the deflated and A3 systems are singular */
    ISM_UNCERT_CONTRACT = 3,  /* Krawczyk did not contract on any box up to the bound */
    ISM_UNCERT_RANK0 = 4,     /* Hessian 0 and the rank-0 system singular (f's cubic term has
                                 a direction along which its Hessian vanishes) */
    ISM_UNCERT_CROSSING = 5,  /* Hessian rank 1 where two or more traced singular curves end
                                 (two whiskers crossing in z² + x²y²): not a contact of two
                                 sheets; the rank-1 system is singular where curves cross */
    ISM_UNCERT_LOOP = 6,      /* a closed curve of zeros of ∇f on f = 0 (a whisker loop) too
                                 small for the curve tracer (the Hessian across it is below
                                 the rank threshold), reported as one of its points; radius
                                 bounds the loop */
    ISM_UNCERT_WHYS
};

typedef struct ism_sing_point {
    double p[3];
    double radius;        /* half-width of the enclosure: the Krawczyk box when certified,
                             else of the candidate cluster */
    int type;             /* enum ism_sing_type */
    bool certified;       /* Krawczyk proved one zero of ∇f in p ± radius (or, for rank 2,
                             of the deflated system: certificate), and the interval of f over
                             that box contains 0 */
    int certificate;      /* enum ism_cert_kind */
    int uncertified_why;  /* enum ism_uncert_why */
    double perturbation;  /* ISM_CERT_DEFLATION: the bound on |ε|; the defining systems:
                             their relative residual at the point (0 otherwise) */
    double exists_radius; /* > 0 on an uncertified contact: a zero of ∇f is proved to lie
                             within this distance of p (Poincaré–Miranda, miranda.h) — no
                             uniqueness, no 1e-9 bound */
    double eig[3];        /* Hessian eigenvalues at p, ascending */
    double residual_f;    /* |f(p)| */
    double residual_grad; /* |∇f(p)| */
    int cones;            /* cones of faces meeting at the point's mesh vertex (set by the
                             conformance pass; -1 until then, 0 when it has no vertex) */
} ism_sing_point;

enum ism_curve_kind {
    ISM_CURVE_DOUBLE = 0,  /* two real sheets cross along it (Hessian indefinite across) */
    ISM_CURVE_WHISKER = 1, /* a 1-D real set with no sheet (Hessian definite across) */
    ISM_CURVE_KINDS
};

enum ism_end_type {
    ISM_END_BOX = 0,     /* leaves the search box */
    ISM_END_PINCH = 1,   /* at a pinch point (the curve changes kind there) */
    ISM_END_TRIPLE = 2,  /* at a triple point (branches meet) */
    ISM_END_POINT = 3,   /* at another singular point of the list */
    ISM_END_LOST = 4,    /* tracing stopped (budget, deadline, no convergence): say so */
    ISM_END_TYPES
};

typedef struct ism_sing_curve {
    int kind;              /* enum ism_curve_kind */
    bool closed;           /* a loop: xyz's last point joins its first (not repeated) */
    size_t n;              /* points */
    double *xyz;           /* 3 per point, each within 1e-9 × diagonal of f = ∇f = 0 */
    int end_type[2];       /* enum ism_end_type of the first and last point (unused when
                              closed) */
    int end_point[2];      /* index into ism_locus.points of the point it ends at, or -1 */
    double split_cell;     /* the cell the octree split its nodes to along it, finer than
                              the depth's (core/singular/curve_cell.h), or 0: the depth's */
    /* Its certificate (core/singular/curve_cert.h): certified when every point passed. */
    bool certified;
    size_t uncertified_points;   /* points that did not pass (all n when not checked) */
    long first_uncertified;      /* index of the first of them; -1 when none, or when the
                                    certification was cut short before this curve */
    double first_residual_f;     /* |f| and |∇f| at that point (0 when none) */
    double first_residual_grad;
    double cert_radius;          /* the largest half-width of a certificate box used */
} ism_sing_curve;

/* A candidate box of the search: neither excluded by intervals nor certified as one point. */
enum ism_lbox_flags {
    ISM_LBOX_PROJECTED = 1, /* q holds a point of ∇f = 0 (Gauss–Newton converged in the box
                               grown by half its width, or an earlier box's such point lying
                               on this box: search.c's project_all) */
    ISM_LBOX_USED = 2,      /* explained by a point, a curve or a sheet */
    ISM_LBOX_UNIQUE = 4,    /* Krawczyk proved exactly one zero of ∇f in the box (which may
                               then be larger than the finest cells); the points stage
                               certifies or drops it */
};

typedef struct ism_lbox {
    double lo[3], hi[3];
    double q[3];            /* the centre projected onto ∇f = 0 (when PROJECTED) */
    uint8_t rank;           /* numerical rank of the Hessian at q (0..3) */
    uint8_t flags;          /* enum ism_lbox_flags */
} ism_lbox;

/* A double sheet: a 2-D zero set of f without a sign change (f = g²), meshed as triangles
 * first_triangle .. first_triangle + triangles of the final mesh. */
typedef struct ism_double_sheet {
    size_t first_triangle, triangles;
    double area;
} ism_double_sheet;

/* The search's default depth (ism_locus_options_default): every preset's points and curves
 * are found at it; the singular stage under a bound never goes shallower (surface.c). */
#define ISM_LOCUS_DEFAULT_DEPTH 7

typedef struct ism_locus_options {
    double box[6];             /* xmin ymin zmin xmax ymax zmax */
    int max_depth;             /* search cells no smaller than box side / 2^max_depth */
    size_t max_boxes;          /* budget of candidate boxes kept (beyond: incomplete) */
    int threads;               /* 0 = online cores */
    const volatile int *cancel;/* polled; non-zero stops the search (incomplete) */
    double deadline_ms;        /* ism_now_ms() past which the stage stops (0 = none) */
    double max_error;          /* the mesh's error bound (0 = none; the halving then
                                  uses a quarter of the finest cell): the conformance's
                                  triangles are measured and halved until within it, and the
                                  untangling leaves no centroid farther (conform_refine.c) */
    int limit_depth;           /* depth.max: no edge of the conformance is halved below its
                                  finest cell (0 = max_depth) */
    size_t conform_work_max;   /* budget of the conformance pass's units of work
                                  (ism_conform_stats.work; 0 = none): beyond, it stops as at
                                  the deadline */
} ism_locus_options;

void ism_locus_options_default(ism_locus_options *o);

typedef struct ism_locus {
    ism_sing_point *points;
    size_t npoints, cap_points;
    ism_sing_curve *curves;
    size_t ncurves, cap_curves;
    ism_lbox *boxes;
    size_t nboxes, cap_boxes;
    ism_double_sheet *sheets;
    size_t nsheets, cap_sheets;
    bool incomplete;            /* cut short (budget, deadline, cancel): what is listed is
                                   right, but something may be missing */
    char incomplete_why[96];
    uint64_t boxes_visited, evals_interval;
    uint64_t evals_jet;         /* every Hessian taken, including those of projection runs
                                   spent for nothing (search.c project_run): work done, not
                                   the answer's size; it moves when the sharing rule does */
    uint64_t centre_dropped;    /* cells the search dropped by f at their centre against the
                                   parent's Taylor form (search.c, children_quad): tests see
                                   that test ran; not in the JSON stats */
    uint64_t grads_batched;     /* cells whose interval gradients the search took in one batch
                                   with their siblings' (search.c pre_gradients), and how many
                                   of those classify then read (none dropped before): tests
                                   see the batch ran and wasted no lane; not in the JSON stats */
    uint64_t grads_batch_read;
    uint64_t centres_batched;   /* cells whose gradient at the centre the search gave to a
                                   batch (search.c: queued by round_take on tapes without
                                   kinks, only where it is read; with kinks pre_gradients
                                   takes every box's with it), and how many of those
                                   smooth_tests then read: tests see no centre is batched
                                   unread or left out of its batch; not in the JSON stats */
    uint64_t centres_batch_read;
    double time_ms;
    double hessian_scale;       /* the largest Hessian norm sampled over the box (set by the
                                   search; 0 = unknown): the absolute scale below which a
                                   Hessian's eigenvalues count as 0 (search.h, ism_sing_rank) */
} ism_locus;

void ism_locus_init(ism_locus *l);
void ism_locus_free(ism_locus *l);

/* Appenders (false when out of memory). The curve takes ownership of xyz (malloc'd). */
bool ism_locus_add_point(ism_locus *l, const ism_sing_point *p);
bool ism_locus_add_curve(ism_locus *l, const ism_sing_curve *c);
bool ism_locus_add_box(ism_locus *l, const ism_lbox *b);
bool ism_locus_add_sheet(ism_locus *l, const ism_double_sheet *s);

/* Whether o's deadline has passed or its cancel flag is set; the first time, marks l
 * incomplete with "deadline reached during <during>" or "cancelled during <during>". */
bool ism_locus_out_of_time(const ism_locus_options *o, ism_locus *l, const char *during);

/* 1 + i when triangle t of the polygoniser's mesh is in double sheet i's range, else 0
 * (O(sheets)). */
uint32_t ism_locus_sheet_of(const ism_locus *l, size_t t);

/* Distance from point i to the rest of the locus: the other points, and the points of the
 * curves that do not end at it (INFINITY when there is nothing else). O(points + curve
 * points). */
double ism_locus_clearance(const ism_locus *l, size_t i);

/* Names used in JSON and stats: "node", "isolated", "cusp", "degenerate", "pinch",
 * "triple"; "double", "whisker"; "box", "pinch", "triple", "point", "lost". */
const char *ism_sing_type_name(int type);
/* "none", "krawczyk", "deflation", "rank-0 system", "rank-1 system", "A3 system"; and
 * the reasons (a sentence each; NULL for ISM_UNCERT_NONE). */
const char *ism_cert_kind_name(int kind);
const char *ism_uncert_why_name(int why);
const char *ism_curve_kind_name(int kind);
const char *ism_end_type_name(int type);

#endif
