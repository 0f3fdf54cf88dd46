/* surface.c — the phases of one surface in order (see surface.h). Each phase is its own
 * module; this file only sequences them and times them. */
#include "core/singular/surface.h"
#include "core/singular/conform.h"
#include "core/singular/covered.h"
#include "core/singular/crossing_angle.h"
#include "core/singular/curve_cell.h"
#include "core/singular/find.h"
#include "core/singular/sheets.h"
#include "core/octree/node_balls.h"
#include "core/util/clock.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The depth's cell: the box's longest side / 2^depth. */
static double finest_cell(const double box[6], int depth)
{
    return ldexp(fmax(box[3] - box[0], fmax(box[4] - box[1], box[5] - box[2])), -depth);
}

/* Under max_error the singular stage's scale (locus search depth, conformance tube and
 * balls, the curves' split cells) is the first depth whose cell c is at most this many E, not
 * depth.max, which is then only a safety limit. Depths step by 2, so the cell used lands
 * anywhere in (k/2, k] E. k trades the tube's width against its cost: a narrower tube means
 * more refill triangles and more of the polygoniser's cut out. It is not what keeps E: the
 * octree's error measure and refinement (core/octree/refine.h) and the conformance refill's
 * own measure against E do that, near points and curves too. A flat chord of span c on a
 * sheet of curvature radius R sags c^2 / (8R) <= E while R >= k c / 8, which covers the
 * smooth sheets beside a double curve but not the cells within about c of a node or pinch
 * point, where R goes to 0. Evidence: at a cell of 4.97 E Whitney, cross-cap, Kummer-4 and the
 * double cone stay within E with the points and curves of k = 4.6 (own and +1e-3 boxes;
 * test_pinch_error.c whitney_at_the_coarsest_singular_cell), and Klein still at 19 E. */
#define SINGULAR_CELLS_PER_E 5.0
/* ... and never shallower than the locus search's own default depth, at which every
 * preset's points and curves are found: a coarse E must not make the search miss one. */
#define SINGULAR_MIN_DEPTH ISM_LOCUS_DEFAULT_DEPTH

int ism_singular_depth(const ism_poly_options *po)
{
    if (!(po->max_error > 0) || po->max_depth <= SINGULAR_MIN_DEPTH)
        return po->max_depth;
    int d = SINGULAR_MIN_DEPTH;
    while (d < po->max_depth && finest_cell(po->box, d) > SINGULAR_CELLS_PER_E * po->max_error)
        d++;
    return d;
}

void ism_locus_options_from_poly(const ism_poly_options *po, ism_locus_options *lo)
{
    ism_locus_options_default(lo);
    memcpy(lo->box, po->box, sizeof lo->box);
    lo->max_depth = ism_singular_depth(po);
    lo->max_error = po->max_error > 0 ? po->max_error : 0;
    lo->limit_depth = po->max_depth;
    lo->threads = po->threads;
    lo->cancel = po->cancel;
    lo->deadline_ms = po->deadline_ms;
}

/* Share of the conformance pass's smallest ball (and tube) in which the polygoniser does not chase
 * hidden pieces: the ball's rim, where the refill meets the polygoniser's mesh, must lie in
 * cells that were chased (the pass widens its cut from there, never narrows it). */
#define QUIET_SHARE 0.8

/* Along a double curve the pass cuts a tube of the same radius: its balls are this far
 * apart at most, in radii (their union then covers a tube of 0.97 of the radius). */
#define QUIET_SPACING 0.5

typedef struct ball_list {
    double (*b)[4];
    size_t n, cap;
} ball_list;

static bool add_ball(ball_list *l, const double p[3], double r)
{
    if (l->n == l->cap) {
        size_t c = l->cap ? 2 * l->cap : 64;
        double (*b)[4] = realloc(l->b, c * sizeof *b);
        if (!b)
            return false;
        l->b = b;
        l->cap = c;
    }
    memcpy(l->b[l->n], p, 3 * sizeof *p);
    l->b[l->n++][3] = r;
    return true;
}

/* Balls along segment a-b (a included, b not), QUIET_SPACING radii apart at most. */
static bool add_segment(ball_list *l, const double a[3], const double b[3], double r)
{
    double d = sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) +
                    (b[2] - a[2]) * (b[2] - a[2]));
    double steps = ceil(d / (QUIET_SPACING * r));
    if (!(steps >= 1 && steps < 1e6))
        steps = 1;
    for (double k = 0; k < steps; k++) {
        double t = k / steps, p[3];
        for (int a3 = 0; a3 < 3; a3++)
            p[a3] = a[a3] + t * (b[a3] - a[a3]);
        if (!add_ball(l, p, r))
            return false;
    }
    return true;
}

/* The balls around the locus where hidden pieces are not chased (see ism_poly_options): one
 * at each point, a row along each curve. malloc'd in *out (NULL when there are none); false
 * when memory ran out. */
static bool quiet_balls(const ism_locus *l, const ism_locus_options *lo, ball_list *out)
{
    memset(out, 0, sizeof *out);
    double r0 = QUIET_SHARE * ism_conform_min_radius(lo), finest = finest_cell(lo->box, lo->max_depth);
    for (size_t i = 0; i < l->npoints; i++)
        if (!add_ball(out, l->points[i].p, r0 * ism_point_curve_cell(l, i, finest) / finest))
            return false;
    for (size_t c = 0; c < l->ncurves; c++) {
        const ism_sing_curve *cu = &l->curves[c];
        double r = r0 * ism_curve_mesh_cell(cu, finest) / finest;
        for (size_t i = 0; i < cu->n; i++) {
            size_t j = i + 1 < cu->n ? i + 1 : cu->closed ? 0 : i;
            if (!add_segment(out, cu->xyz + 3 * i, cu->xyz + 3 * j, r))
                return false;
        }
    }
    return true;
}

/* Around a certified node the octree's nodes are split until they are at most the node's
 * clearance (the distance to the rest of the locus) / NODE_CELLS across, within
 * NODE_REACH × the clearance of it. Where the surface between two nodes is a piece smaller
 * than the depth's cells (kummer-4-nodes: an inner piece spanning its 4 nodes, 0.48
 * apart), that piece is at most as wide as the nodes are apart; 4 cells between two nodes
 * cross it with edges at any lattice offset (measured: 8 gave the same counts with 3x the
 * triangles), and the conformance ball (0.45 clearance) then spans 1.8 of them. At depths
 * whose cells are already that fine nothing changes (node_balls). */
#define NODE_CELLS 4.0
/* The ball reaches the neighbouring nodes: a piece joining two nodes is fine all along. */
#define NODE_REACH 1.0

/* Along a double curve that asks for cells finer than the depth's (curve_cell.h) the nodes
 * are split down to that cell within CURVE_REACH of its cells of the curve: the tube the
 * conformance pass cuts there (2.5 cells, widened up to ×1.4⁶ until its rim is clear of the
 * other sheet) then lies in split nodes, its rim on triangles of the curve's scale. */
#define CURVE_REACH 8.0
/* The cell is one of the octree's (curve_cell.h): nodes are split while larger than this
 * many of it, so one of its size stays whole whatever the rounding of its sides. */
#define SPLIT_ABOVE 1.5
/* ... the balls along it at most this many radii apart (their union then holds a tube of
 * 0.97 of the radius). */
#define CURVE_BALL_SPACING 0.5

/* Appends a ball (centre p, radius r, cell) at out[*m] unless *m reached ISM_NODE_BALLS_MAX
 * (then only counts it). */
static void put_ball(double (*out)[ISM_NODE_BALL_FIELDS], size_t *m, const double p[3], double r,
                     double cell)
{
    if (*m < ISM_NODE_BALLS_MAX) {
        memcpy(out[*m], p, 3 * sizeof *p);
        out[*m][ISM_NODE_BALL_R] = r;
        out[*m][ISM_NODE_BALL_CELL] = cell;
    }
    (*m)++;
}

/* Appends the balls along the double curves that ask for cells finer than `finest` (by
 * their span and the angle their sheets cross at, measured with f on ws) to out[0 .. n): at
 * every point and along each segment, CURVE_BALL_SPACING radii apart at most. A curve whose
 * balls do not all fit under ISM_NODE_BALLS_MAX gets none (the mesh there is then the
 * depth's). Returns the new count. */
static size_t curve_balls(const ism_tape *f, ism_eval_ws *ws, ism_locus *l, double finest,
                          double (*out)[ISM_NODE_BALL_FIELDS], size_t n)
{
    for (size_t k = 0; k < l->ncurves; k++) {
        ism_sing_curve *cu = &l->curves[k];
        if (cu->kind != ISM_CURVE_DOUBLE || cu->n < 2)
            continue;
        double tan_phi = ism_curve_crossing_tan(f, ws, cu->xyz, cu->n);
        double cell = ism_curve_cell(cu, finest, tan_phi);
        if (!(cell < finest))
            continue;
        /* fmax: a NAN angle leaves the reach as it is */
        double r = CURVE_REACH * fmax(1, ISM_CURVE_FULL_TAN / tan_phi) * cell, since = INFINITY;
        size_t m = n, segs = cu->closed ? cu->n : cu->n - 1;
        for (size_t i = 0; i <= segs && m <= ISM_NODE_BALLS_MAX; i++) {
            const double *p = cu->xyz + 3 * (i % cu->n);
            if (i > 0) {
                const double *a = cu->xyz + 3 * (i - 1);
                double len = sqrt(ism_sqdist3(a, p));
                for (double t = CURVE_BALL_SPACING * r - since; t < len; t += CURVE_BALL_SPACING * r) {
                    double q[3];
                    for (int j = 0; j < 3; j++)
                        q[j] = a[j] + t / len * (p[j] - a[j]);
                    put_ball(out, &m, q, r, SPLIT_ABOVE * cell);
                }
                since = fmod(since + len, CURVE_BALL_SPACING * r);
            }
            if (i == 0 || i == segs) {
                put_ball(out, &m, p, r, SPLIT_ABOVE * cell);
                since = 0;
            }
        }
        if (m <= ISM_NODE_BALLS_MAX) {
            n = m;
            cu->split_cell = cell;
        }
    }
    return n;
}

/* The balls for the certified nodes with a finite clearance whose cell is finer than the
 * depth's (the first ISM_NODE_BALLS_MAX in the locus's order). Where the depth's cells are
 * that fine already, the flatness test refines round the apex to depth.max by itself, and
 * the octree is left as it was. */
static size_t node_balls(const ism_tape *f, ism_eval_ws *ws, ism_locus *l,
                         const ism_poly_options *po, double (*out)[ISM_NODE_BALL_FIELDS])
{
    double finest = finest_cell(po->box, ism_singular_depth(po));
    size_t n = 0;
    for (size_t i = 0; i < l->npoints && n < ISM_NODE_BALLS_MAX; i++) {
        const ism_sing_point *p = &l->points[i];
        if (p->type != ISM_SING_NODE || !p->certified)
            continue;
        double c = ism_locus_clearance(l, i);
        if (!isfinite(c) || !(c / NODE_CELLS < finest))
            continue;
        memcpy(out[n], p->p, 3 * sizeof *p->p);
        out[n][ISM_NODE_BALL_R] = NODE_REACH * c;
        out[n][ISM_NODE_BALL_CELL] = c / NODE_CELLS;
        n++;
    }
    return curve_balls(f, ws, l, finest, out, n);
}

/* The locus's points for the dual mesher (poly_options.dual_points: x, y, z, clearance,
 * nappes) when it is isolated points only, every one certified and a node or an isolated
 * point; *other when it is points only but one is not. malloc'd (NULL with a count of 0
 * otherwise); false when out of memory. */
static bool dual_points(const ism_locus *l, double (**out)[5], size_t *n, bool *other)
{
    *out = NULL;
    *n = 0;
    *other = false;
    if (l->incomplete || l->ncurves || !l->npoints)
        return true;
    for (size_t i = 0; i < l->npoints; i++) {
        const ism_sing_point *p = &l->points[i];
        if (!p->certified || (p->type != ISM_SING_NODE && p->type != ISM_SING_ISOLATED)) {
            *other = true;
            return true;
        }
    }
    double (*pts)[5] = malloc(l->npoints * sizeof *pts);
    if (!pts)
        return false;
    for (size_t i = 0; i < l->npoints; i++) {
        memcpy(pts[i], l->points[i].p, 3 * sizeof(double));
        pts[i][3] = ism_locus_clearance(l, i);
        pts[i][4] = l->points[i].type == ISM_SING_NODE ? 2 : 0;
    }
    *out = pts;
    *n = l->npoints;
    return true;
}

enum ism_poly_status ism_mesh_surface(const ism_tape *f, const ism_poly_options *po,
                                      ism_mesh *mesh, ism_locus *locus, ism_poly_stats *ps,
                                      ism_conform_stats *cs, ism_surface_times *times,
                                      ism_error *err)
{
    memset(times, 0, sizeof *times);
    memset(cs, 0, sizeof *cs);
    if (!ism_poly_options_check(po, err))
        return ISM_POLY_BAD_OPTIONS;
    ism_locus_options lo;
    ism_locus_options_from_poly(po, &lo);
    double t0 = ism_now_ms(), c0 = ism_cpu_ms();
    if (!ism_locus_find(f, &lo, locus, err))
        return ISM_POLY_NO_MEMORY;
    double t1 = ism_now_ms(), c1 = ism_cpu_ms();
    ism_poly_options pq = *po;
    /* the split balls first: they record the curves' split cells, which size the quiet balls */
    double(*nodes)[ISM_NODE_BALL_FIELDS] = malloc(ISM_NODE_BALLS_MAX * sizeof *nodes);
    ism_eval_ws *ws = ism_eval_ws_new(f);
    if (!nodes || !ws) {
        free(nodes);
        ism_eval_ws_free(ws);
        return ISM_POLY_NO_MEMORY;
    }
    pq.nnode_balls = node_balls(f, ws, locus, po, nodes);
    ism_eval_ws_free(ws);
    pq.node_balls = (const double (*)[ISM_NODE_BALL_FIELDS])nodes;
    ball_list balls;
    if (!quiet_balls(locus, &lo, &balls)) {
        free(balls.b);
        free(nodes);
        return ISM_POLY_NO_MEMORY;
    }
    double none[1][4] = {{0, 0, 0, 0}}; /* the locus is known, and empty */
    pq.quiet = balls.n ? (const double (*)[4])balls.b : (const double (*)[4])none;
    pq.nquiet = balls.n;
    if (locus->incomplete) { /* points may be missing: chase as without a locus (bounded) */
        pq.quiet = NULL;
        pq.nquiet = 0;
    }
    double (*points)[5];
    if (!dual_points(locus, &points, &pq.ndual_points, &pq.dual_points_other)) {
        free(balls.b);
        free(nodes);
        return ISM_POLY_NO_MEMORY;
    }
    pq.dual_points = (const double (*)[5])points;
    enum ism_poly_status st = ism_polygonise(f, &pq, mesh, ps, err);
    free(points);
    free(balls.b);
    free(nodes);
    double t2 = ism_now_ms(), c2 = ism_cpu_ms();
    times->polygonise_ms = t2 - t1;
    times->polygonise_cpu_ms = c2 - c1;
    if (st != ISM_POLY_OK)
        return st;
    if (po->cancel && *po->cancel)
        return ISM_POLY_CANCELLED;
    /* Conform first: it may remove and renumber the polygoniser's triangles, while the
     * double sheets are appended after them and recorded as triangle ranges; they leave out
     * the boxes the polygoniser already meshed (a double sheet on a lattice plane). */
    bool fanned = ps->mesher == ISM_MESHER_DUAL && pq.ndual_points;
    if (fanned) /* the dual mesh fanned every node's two nappes to one vertex at it
                   (core/octree/dual_balls.h): conformed already; isolated points carry no
                   sheet (no vertex, as conform leaves them) */
        for (size_t i = 0; i < locus->npoints; i++) {
            bool node = locus->points[i].type == ISM_SING_NODE;
            locus->points[i].cones = node ? 2 : -1;
            cs->points_conformed += node;
            cs->points_skipped += !node;
        }
    if ((!fanned && !ism_conform_mesh(f, &lo, locus, mesh, cs, err)) ||
        !ism_locus_mark_covered(locus, &lo, mesh) ||
        !ism_sing_double_sheets_from_search(f, &lo, locus, mesh, err) ||
        !ism_mesh_drop_loose(mesh))
        return ISM_POLY_NO_MEMORY;
    times->singular_ms = (t1 - t0) + (ism_now_ms() - t2);
    times->singular_cpu_ms = (c1 - c0) + (ism_cpu_ms() - c2);
    locus->time_ms = times->singular_ms;
    return ISM_POLY_OK;
}
