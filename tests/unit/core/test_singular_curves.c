/* test_singular_curves.c — tracing singular curves (core/singular/curves.h) on surfaces whose
 * singular locus is known in closed form: a whisker circle, two spheres crossing in a
 * circle, xyz = 0, Steiner's Roman surface, the Whitney umbrella and the cross-cap. The seed
 * boxes are made here, independently of the interval search: the search's lattice cells that
 * a parametrisation of the known curve passes through, each with its centre projected onto
 * ∇f = 0 by Gauss–Newton. Every case runs in its box as given and shifted off the lattice by
 * 1e-3 and by 0.37 of a finest cell. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/eval/eval.h"
#include "core/singular/curves.h"
#include "core/singular/find.h"
#include "core/util/sym3.h"
#include "core/util/vec3.h"
#include "tests/unit/placements.h"

#define DEPTH 6
#define PI 3.14159265358979323846

/* Each point of a curve must lie within this × box diagonal of the locus (curves.h). */
#define ON_LOCUS 1e-9

/* The seed boxes' rank: Hessian eigenvalues above this fraction of the largest count. */
#define SEED_RANK_REL 1e-3

typedef struct fixture {
    ism_tape *t;
    ism_eval_ws *ws;
    ism_locus_options o;
    ism_locus l;
    double cell, diag;
    uint64_t *keys; /* lattice cells already seeded: an open-addressing set, 0 = empty */
    size_t nkeys, cap_keys;
    bool thick;     /* seed the 26 neighbours of each cell too, as an interval search would */
} fixture;

static const double SHIFTS_CELLS[] = {0.0, -1.0, PF_IRR}; /* -1: the 1e-3 shift */
#define NSHIFTS 3

/* Sets up f over box moved by the shift-th shift (in every axis); returns the shift. */
static double setup_lets(fixture *fx, const char *expr, const ism_let *lets, size_t nlets,
                         const double box[6], int shift_index)
{
    memset(fx, 0, sizeof *fx);
    fx->cell = ldexp(box[3] - box[0], -DEPTH); /* the test boxes are cubes */
    double shift = SHIFTS_CELLS[shift_index] < 0 ? 1e-3 : SHIFTS_CELLS[shift_index] * fx->cell;
    ism_error err;
    fx->t = ism_tape_compile(expr, NULL, 0, lets, nlets, NULL, &err);
    cr_assert_not_null(fx->t, "%s: %s", expr, err.message);
    fx->ws = ism_eval_ws_new(fx->t);
    ism_locus_options_default(&fx->o);
    for (int k = 0; k < 6; k++)
        fx->o.box[k] = box[k] + shift;
    fx->diag = ism_box_diagonal(box);
    fx->o.max_depth = DEPTH;
    ism_locus_init(&fx->l);
    return shift;
}

static double setup(fixture *fx, const char *expr, const double box[6], int shift_index)
{
    return setup_lets(fx, expr, NULL, 0, box, shift_index);
}

static void teardown(fixture *fx)
{
    ism_locus_free(&fx->l);
    ism_eval_ws_free(fx->ws);
    ism_tape_free(fx->t);
    free(fx->keys);
}

/* Gauss–Newton on ∇f = 0 from p (minimum-norm steps through the Hessian's pseudo-inverse,
 * the smallest eigenvalue and those below the rank threshold dropped: the boxes made here
 * are on curves, along which the step must not slide): the search's projection of a
 * candidate box's centre. False when it does not converge. */
static bool project(fixture *fx, double p[3])
{
    for (int it = 0; it < 100; it++) {
        double g[3], h[6], eig[3], vec[3][3], step[3] = {0, 0, 0};
        ism_eval_hessian(fx->t, fx->ws, p[0], p[1], p[2], g, h);
        ism_sym3_eigen(h, eig, vec);
        double m = fmax(fabs(eig[0]), fabs(eig[2]));
        int small = 0;
        for (int i = 1; i < 3; i++)
            if (fabs(eig[i]) < fabs(eig[small]))
                small = i;
        for (int i = 0; i < 3; i++)
            if (i != small && fabs(eig[i]) > SEED_RANK_REL * m) {
                double c = (vec[i][0] * g[0] + vec[i][1] * g[1] + vec[i][2] * g[2]) / eig[i];
                for (int k = 0; k < 3; k++)
                    step[k] -= c * vec[i][k];
            }
        for (int k = 0; k < 3; k++)
            p[k] += step[k];
        if (sqrt(step[0] * step[0] + step[1] * step[1] + step[2] * step[2]) < 1e-14 * fx->diag)
            return true;
    }
    return false;
}

/* Inserts key (non-zero) into the set; false when it was there. */
static bool key_insert(fixture *fx, uint64_t key)
{
    if (2 * (fx->nkeys + 1) > fx->cap_keys) {
        uint64_t *old = fx->keys;
        size_t cap = fx->cap_keys;
        fx->cap_keys = cap ? 2 * cap : 1024;
        fx->keys = calloc(fx->cap_keys, sizeof *fx->keys);
        cr_assert_not_null(fx->keys);
        fx->nkeys = 0;
        for (size_t i = 0; i < cap; i++)
            if (old[i])
                key_insert(fx, old[i]);
        free(old);
    }
    size_t i = (size_t)(key * 0x9E3779B97F4A7C15ull >> 20) & (fx->cap_keys - 1);
    for (; fx->keys[i]; i = (i + 1) & (fx->cap_keys - 1))
        if (fx->keys[i] == key)
            return false;
    fx->keys[i] = key;
    fx->nkeys++;
    return true;
}

/* Adds the search cell c as a candidate box (once), with q and rank. */
static void seed_lattice_cell(fixture *fx, const long c[3])
{
    for (int k = 0; k < 3; k++)
        if (c[k] < 0 || c[k] >= (1L << DEPTH))
            return;
    if (!key_insert(fx, 1 + ((uint64_t)c[0] << 42 | (uint64_t)c[1] << 21 | (uint64_t)c[2])))
        return;
    ism_lbox b = {0};
    for (int k = 0; k < 3; k++) {
        b.lo[k] = fx->o.box[k] + c[k] * fx->cell;
        b.hi[k] = b.lo[k] + fx->cell;
        b.q[k] = 0.5 * (b.lo[k] + b.hi[k]);
    }
    bool inside = project(fx, b.q);
    for (int k = 0; k < 3; k++) /* converged within the box grown by half its width */
        inside = inside && b.q[k] >= b.lo[k] - 0.5 * fx->cell && b.q[k] <= b.hi[k] + 0.5 * fx->cell;
    if (inside) {
        double g[3], h[6], eig[3];
        ism_eval_hessian(fx->t, fx->ws, b.q[0], b.q[1], b.q[2], g, h);
        ism_sym3_eigen(h, eig, NULL);
        b.rank = (uint8_t)ism_sym3_rank(eig, SEED_RANK_REL);
        b.flags = ISM_LBOX_PROJECTED;
    }
    cr_assert(ism_locus_add_box(&fx->l, &b));
}

/* Adds the search cell containing p (and its neighbours when fx->thick). */
static void seed_cell(fixture *fx, const double p[3])
{
    long c[3];
    for (int k = 0; k < 3; k++)
        c[k] = (long)floor((p[k] - fx->o.box[k]) / fx->cell);
    int r = fx->thick ? 1 : 0;
    for (long i = -r; i <= r; i++)
        for (long j = -r; j <= r; j++)
            for (long k = -r; k <= r; k++)
                seed_lattice_cell(fx, (long[3]){c[0] + i, c[1] + j, c[2] + k});
}

typedef void (*curve_fn)(const void *ctx, double s, double out[3]);

/* Seeds every search cell the curve g(s), s in [s0, s1], passes through (sampled at an
 * eighth of a cell; speed bounds |g'|). */
static void cover(fixture *fx, curve_fn g, const void *ctx, double s0, double s1, double speed)
{
    double ds = fx->cell / (8.0 * speed);
    for (double s = s0; s <= s1; s += ds) {
        double p[3];
        g(ctx, s, p);
        seed_cell(fx, p);
    }
}

static void x_axis(const void *ctx, double s, double p[3]) { (void)ctx, p[0] = s, p[1] = 0, p[2] = 0; }
static void y_axis(const void *ctx, double s, double p[3]) { (void)ctx, p[0] = 0, p[1] = s, p[2] = 0; }
static void z_axis(const void *ctx, double s, double p[3]) { (void)ctx, p[0] = 0, p[1] = 0, p[2] = s; }
static void whisker_circle(const void *ctx, double s, double p[3]) { (void)ctx, p[0] = 0.5 * cos(s), p[1] = 0.5 * sin(s), p[2] = 0; }
static void spheres_circle(const void *ctx, double s, double p[3])
{
    (void)ctx;
    double r = sqrt(0.75);
    p[0] = 0, p[1] = r * cos(s), p[2] = r * sin(s);
}

static void run(fixture *fx)
{
    ism_error err;
    cr_assert(ism_sing_trace_curves(fx->t, &fx->o, &fx->l, &err), "%s", err.message);
    cr_assert_not(fx->l.incomplete, "incomplete: %s", fx->l.incomplete_why);
}

static double curve_length(const ism_sing_curve *c)
{
    double len = 0;
    size_t segs = c->closed ? c->n : c->n - 1;
    for (size_t i = 0; i < segs; i++) {
        const double *a = c->xyz + 3 * i, *b = c->xyz + 3 * ((i + 1) % c->n);
        len += sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                    (a[2] - b[2]) * (a[2] - b[2]));
    }
    return len;
}

/* Largest distance from the curve's vertices, and from its edges' midpoints, to the locus
 * (given as a distance function). */
typedef double (*dist_fn)(const double p[3]);
static void curve_error(const ism_sing_curve *c, dist_fn d, double *vert, double *mid)
{
    *vert = *mid = 0;
    size_t segs = c->closed ? c->n : c->n - 1;
    for (size_t i = 0; i < c->n; i++)
        *vert = fmax(*vert, d(c->xyz + 3 * i));
    for (size_t i = 0; i < segs; i++) {
        const double *a = c->xyz + 3 * i, *b = c->xyz + 3 * ((i + 1) % c->n);
        double m[3] = {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
        *mid = fmax(*mid, d(m));
    }
}

/* Every seed box whose projected point lies on the zero set inside the search box is
 * explained (a neighbour cell's q may have gone to a critical point off f = 0, or to the
 * curve beyond the box's face: those are no traced curve's). */
static void assert_boxes_used(fixture *fx)
{
    for (size_t b = 0; b < fx->l.nboxes; b++) {
        const ism_lbox *bx = &fx->l.boxes[b];
        bool inside = true;
        for (int k = 0; k < 3; k++)
            inside = inside && bx->q[k] >= fx->o.box[k] && bx->q[k] <= fx->o.box[k + 3];
        if ((bx->flags & ISM_LBOX_PROJECTED) && bx->rank == 2 && inside &&
            fabs(ism_eval_point(fx->t, fx->ws, bx->q[0], bx->q[1], bx->q[2])) <= 1e-12)
            cr_assert(bx->flags & ISM_LBOX_USED, "seed box %zu (q = %g %g %g) not explained", b,
                      bx->q[0], bx->q[1], bx->q[2]);
    }
}

static size_t count_points(const fixture *fx, int type)
{
    size_t n = 0;
    for (size_t i = 0; i < fx->l.npoints; i++)
        n += fx->l.points[i].type == type;
    return n;
}

/* The sagitta of a chord of length ≤ one cell (a step is ≤ half a cell; a loop's closing
 * chord ≤ one) on a circle of radius r, plus the vertices' own tolerance. */
static double chord_bound(const fixture *fx, double r)
{
    return fx->cell * fx->cell / (8 * r) + ON_LOCUS * fx->diag;
}

/* Steps: no vertex repeated, none more than ~half a cell from the next (curves.h). */
static void assert_steps(const fixture *fx, const ism_sing_curve *c)
{
    size_t segs = c->closed ? c->n : c->n - 1;
    for (size_t i = 0; i < segs; i++) {
        const double *a = c->xyz + 3 * i, *b = c->xyz + 3 * ((i + 1) % c->n);
        double d = hypot(a[0] - b[0], hypot(a[1] - b[1], a[2] - b[2]));
        cr_assert(d > 0 && d <= 0.6 * fx->cell, "segment %zu of length %g (cell %g)", i, d,
                  fx->cell);
    }
}

static void assert_all_steps(fixture *fx)
{
    for (size_t i = 0; i < fx->l.ncurves; i++)
        assert_steps(fx, &fx->l.curves[i]);
}

/* ---- (x² + y² − 0.25)² + z²: a circle of radius 0.5, f > 0 around it: one closed whisker */

static double whisker_dist(const double p[3]) { return hypot(hypot(p[0], p[1]) - 0.5, p[2]); }

Test(singular_curves, whisker_circle)
{
    static const double box[6] = {-1, -1, -1, 1, 1, 1};
    for (int s = 0; s < NSHIFTS; s++) {
        fixture fx;
        double sh = setup(&fx, "(x^2 + y^2 - 0.25)^2 + z^2", box, s);
        cover(&fx, whisker_circle, NULL, 0, 2 * PI, 0.5);
        run(&fx);
        cr_assert_eq(fx.l.ncurves, 1, "shift %g: %zu curves", sh, fx.l.ncurves);
        cr_assert_eq(fx.l.npoints, 0, "shift %g: %zu points", sh, fx.l.npoints);
        const ism_sing_curve *c = &fx.l.curves[0];
        cr_assert(c->closed, "shift %g: not closed", sh);
        cr_assert_eq(c->kind, ISM_CURVE_WHISKER, "shift %g", sh);
        double len = curve_length(c), vert, mid;
        cr_assert_lt(fabs(len - PI), 0.005 * PI, "shift %g: length %.9f vs pi", sh, len);
        curve_error(c, whisker_dist, &vert, &mid);
        cr_assert_leq(vert, ON_LOCUS * fx.diag, "shift %g: vertex %g off the circle", sh, vert);
        cr_assert_leq(mid, chord_bound(&fx, 0.5), "shift %g: midpoint %g off", sh, mid);
        assert_boxes_used(&fx);
        assert_all_steps(&fx);
        teardown(&fx);
    }
}

/* ---- whisker loops smaller than a search cell, ((x − a)² + (y − b)² − r²)² + (z − c)², r = 0.15
 * and 0.45 of a cell, off every lattice plane: one closed whisker each, every vertex on the
 * circle, the length 2πr within 0.5% (the polyline keeps the vertices its turning needs).
 * Their Hessian across is diag(8r², 2): a relative rank test of 1e-3 calls it rank 1 below
 * r ≈ 0.016, so the seeds are made here from the closed form (q: the circle's point nearest
 * the cell's centre, 1e-4 r off it), rank 2. */

typedef struct small_loop { double c[3], r; } small_loop;

static void small_loop_at(const void *ctx, double s, double p[3])
{
    const small_loop *l = ctx;
    p[0] = l->c[0] + l->r * cos(s), p[1] = l->c[1] + l->r * sin(s), p[2] = l->c[2];
}

Test(singular_curves, whisker_loops_smaller_than_a_cell)
{
    static const double box[6] = {-1, -1, -1, 1, 1, 1};
    for (int k = 0; k < 2; k++)
        for (int s = 0; s < NSHIFTS; s++) {
            fixture fx;
            double cell = ldexp(2.0, -DEPTH);
            small_loop l = {{0.1037, 0.2011, 0.0529}, (k ? 0.45 : 0.15) * cell};
            char expr[256];
            snprintf(expr, sizeof expr, "((x - %.17g)^2 + (y - %.17g)^2 - %.17g)^2 + (z - %.17g)^2",
                     l.c[0], l.c[1], l.r * l.r, l.c[2]);
            double sh = setup(&fx, expr, box, s);
            cover(&fx, small_loop_at, &l, 0, 2 * PI, l.r);
            for (size_t b = 0; b < fx.l.nboxes; b++) {
                ism_lbox *x = &fx.l.boxes[b];
                double d[2] = {0.5 * (x->lo[0] + x->hi[0]) - l.c[0], 0.5 * (x->lo[1] + x->hi[1]) - l.c[1]};
                double len = hypot(d[0], d[1]);
                x->q[0] = l.c[0] + l.r * d[0] / len + 1e-4 * l.r;
                x->q[1] = l.c[1] + l.r * d[1] / len;
                x->q[2] = l.c[2] - 1e-4 * l.r;
                x->rank = 2;
                x->flags = ISM_LBOX_PROJECTED;
            }
            run(&fx);
            cr_assert_eq(fx.l.ncurves, 1, "r %g, shift %g: %zu curves", l.r, sh, fx.l.ncurves);
            const ism_sing_curve *c = &fx.l.curves[0];
            cr_assert(c->closed && c->kind == ISM_CURVE_WHISKER, "r %g, shift %g", l.r, sh);
            double err = 0;
            for (size_t i = 0; i < c->n; i++) {
                const double *p = c->xyz + 3 * i;
                err = fmax(err, hypot(hypot(p[0] - l.c[0], p[1] - l.c[1]) - l.r, p[2] - l.c[2]));
            }
            cr_assert_leq(err, ON_LOCUS * fx.diag, "r %g, shift %g: vertex %g off", l.r, sh, err);
            double len = curve_length(c);
            cr_assert_lt(fabs(len - 2 * PI * l.r), 0.005 * 2 * PI * l.r, "r %g, shift %g: length %g",
                         l.r, sh, len);
            teardown(&fx);
        }
}

/* ---- two unit spheres centred at x = ±0.5 cross in the circle x = 0, y² + z² = 0.75 */

static double spheres_dist(const double p[3]) { return hypot(p[0], hypot(p[1], p[2]) - sqrt(0.75)); }

Test(singular_curves, two_spheres_cross_in_a_double_circle)
{
    static const double box[6] = {-1, -1, -1, 1, 1, 1};
    static const char expr[] = "((x-0.5)^2 + y^2 + z^2 - 1)*((x+0.5)^2 + y^2 + z^2 - 1)";
    for (int s = 0; s < NSHIFTS; s++) {
        fixture fx;
        double sh = setup(&fx, expr, box, s);
        cover(&fx, spheres_circle, NULL, 0, 2 * PI, sqrt(0.75));
        run(&fx);
        cr_assert_eq(fx.l.ncurves, 1, "shift %g: %zu curves", sh, fx.l.ncurves);
        cr_assert_eq(fx.l.npoints, 0, "shift %g: %zu points", sh, fx.l.npoints);
        const ism_sing_curve *c = &fx.l.curves[0];
        cr_assert(c->closed, "shift %g: not closed", sh);
        cr_assert_eq(c->kind, ISM_CURVE_DOUBLE, "shift %g", sh);
        double vert, mid, rsum = 0;
        curve_error(c, spheres_dist, &vert, &mid);
        cr_assert_leq(vert, ON_LOCUS * fx.diag, "shift %g: vertex %g off the circle", sh, vert);
        cr_assert_leq(mid, chord_bound(&fx, sqrt(0.75)), "shift %g: midpoint %g off", sh, mid);
        for (size_t i = 0; i < c->n; i++)
            rsum += hypot(c->xyz[3 * i + 1], c->xyz[3 * i + 2]);
        cr_assert_lt(fabs(rsum / (double)c->n - sqrt(0.75)), 1e-6, "shift %g: radius", sh);
        cr_assert_lt(fabs(curve_length(c) - 2 * PI * sqrt(0.75)), 0.005 * 2 * PI, "shift %g", sh);
        assert_boxes_used(&fx);
        assert_all_steps(&fx);
        teardown(&fx);
    }
}

/* ---- the seed paper's figure-8 Klein bottle h·(g² − 8z²) + 16xz·g, g = x² + y² + z² − 2y − 1,
 * h = g + 4y: on g = z = 0 (the circle x² + (y − 1)² = 2 in z = 0) ∇f = 0, and the Hessian
 * across, the quadratic form h·g² − 8h·z² + 16x·z·g in (g, z), has determinant
 * −8h² − 64x² < 0 (never both 0 on the circle): one closed double curve. */

static double klein_dist(const double p[3]) { return hypot(p[2], hypot(p[0], p[1] - 1) - sqrt(2)); }
static void klein_circle(const void *ctx, double s, double p[3]) { (void)ctx, p[0] = sqrt(2) * cos(s), p[1] = 1 + sqrt(2) * sin(s), p[2] = 0; }

Test(singular_curves, klein_bottle_double_circle)
{
    static const double box[6] = {-4, -4, -4, 4, 4, 4};
    static const char expr[] = "(x^2 + y^2 + z^2 + 2*y - 1)*((x^2 + y^2 + z^2 - 2*y - 1)^2 - 8*z^2)"
                               " + 16*x*z*(x^2 + y^2 + z^2 - 2*y - 1)";
    for (int s = 0; s < NSHIFTS; s++) {
        fixture fx;
        double sh = setup(&fx, expr, box, s);
        cover(&fx, klein_circle, NULL, 0, 2 * PI, sqrt(2));
        run(&fx);
        cr_assert_eq(fx.l.ncurves, 1, "shift %g: %zu curves", sh, fx.l.ncurves);
        cr_assert_eq(fx.l.npoints, 0, "shift %g: %zu points", sh, fx.l.npoints);
        const ism_sing_curve *c = &fx.l.curves[0];
        cr_assert(c->closed && c->kind == ISM_CURVE_DOUBLE, "shift %g", sh);
        double vert, mid;
        curve_error(c, klein_dist, &vert, &mid);
        cr_assert_leq(vert, ON_LOCUS * fx.diag, "shift %g: vertex %g off the circle", sh, vert);
        cr_assert_leq(mid, chord_bound(&fx, sqrt(2)), "shift %g: midpoint %g off", sh, mid);
        cr_assert_lt(fabs(curve_length(c) - 2 * PI * sqrt(2)), 0.005 * 2 * PI * sqrt(2), "shift %g", sh);
        assert_boxes_used(&fx);
        assert_all_steps(&fx);
        teardown(&fx);
    }
}

/* ---- curves along the coordinate axes */

typedef struct axis_part {
    int axis, sign;     /* the line it runs along, the side of 0 it is on */
    double lo, hi;      /* its extent along the line (signed) */
    double off;         /* largest distance of a vertex from the line */
} axis_part;

static const double AXES[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};

/* Which of the lines through 0 along dirs[k] (unit) the curve runs along, and how. */
static axis_part line_summary(const ism_sing_curve *c, const double dirs[3][3])
{
    axis_part a = {0, 0, 0, 0, 0};
    double ext = -1;
    for (int k = 0; k < 3; k++) {
        double lo = INFINITY, hi = -INFINITY;
        for (size_t i = 0; i < c->n; i++) {
            const double *p = c->xyz + 3 * i;
            double t = p[0] * dirs[k][0] + p[1] * dirs[k][1] + p[2] * dirs[k][2];
            lo = fmin(lo, t), hi = fmax(hi, t);
        }
        if (hi - lo > ext)
            ext = hi - lo, a.axis = k, a.lo = lo, a.hi = hi;
    }
    a.sign = a.lo + a.hi > 0 ? 1 : -1;
    const double *d = dirs[a.axis];
    for (size_t i = 0; i < c->n; i++) {
        const double *p = c->xyz + 3 * i;
        double t = p[0] * d[0] + p[1] * d[1] + p[2] * d[2];
        a.off = fmax(a.off, hypot(p[0] - t * d[0], hypot(p[1] - t * d[1], p[2] - t * d[2])));
    }
    return a;
}

static axis_part axis_summary(const ism_sing_curve *c) { return line_summary(c, AXES); }

/* The curve's ends are {t0, t1} in either order. */
static bool ends_are(const ism_sing_curve *c, int t0, int t1)
{
    return !c->closed && ((c->end_type[0] == t0 && c->end_type[1] == t1) ||
                          (c->end_type[0] == t1 && c->end_type[1] == t0));
}

/* The end of type `type` of a curve: its vertex. */
static const double *end_vertex(const ism_sing_curve *c, int type)
{
    return c->end_type[0] == type ? c->xyz : c->xyz + 3 * (c->n - 1);
}

static int end_point_of(const ism_sing_curve *c, int type)
{
    return c->end_type[0] == type ? c->end_point[0] : c->end_point[1];
}

/* Index of the point of this type within tol of p, or -1. */
static int point_at(const fixture *fx, int type, const double p[3], double tol)
{
    for (size_t i = 0; i < fx->l.npoints; i++) {
        const double *q = fx->l.points[i].p;
        if (fx->l.points[i].type == type &&
            hypot(q[0] - p[0], hypot(q[1] - p[1], q[2] - p[2])) <= tol)
            return (int)i;
    }
    return -1;
}

static void cover_axes(fixture *fx, double reach)
{
    cover(fx, x_axis, NULL, -reach, reach, 1);
    cover(fx, y_axis, NULL, -reach, reach, 1);
    cover(fx, z_axis, NULL, -reach, reach, 1);
}

/* The curve's BOX end lies exactly on a face of the box. */
static void assert_box_end(const fixture *fx, const ism_sing_curve *c)
{
    const double *e = end_vertex(c, ISM_END_BOX);
    bool on = false;
    for (int k = 0; k < 6; k++)
        on = on || e[k % 3] == fx->o.box[k];
    cr_assert(on, "box end %.17g %.17g %.17g on no face", e[0], e[1], e[2]);
}

/* xyz = 0: the three coordinate planes. Their pairwise intersections, the axes, are double
 * lines (Hessian across the x axis [[0, x], [x, 0]]: indefinite); at the origin the Hessian
 * vanishes and the three axes meet: a triple point, six half-axis branches. */
Test(singular_curves, xyz_six_branches_meet_at_one_triple_point)
{
    static const double box[6] = {-1, -1, -1, 1, 1, 1};
    static const double origin[3] = {0, 0, 0};
    for (int s = 0; s < NSHIFTS; s++) {
        fixture fx;
        double sh = setup(&fx, "x*y*z", box, s);
        cover_axes(&fx, 2);
        run(&fx);
        double tol = ON_LOCUS * fx.diag;
        cr_assert_eq(fx.l.npoints, 1, "shift %g: %zu points", sh, fx.l.npoints);
        int tp = point_at(&fx, ISM_SING_TRIPLE, origin, tol);
        cr_assert_eq(tp, 0, "shift %g: no triple point at the origin", sh);
        cr_assert_eq(fx.l.ncurves, 6, "shift %g: %zu curves", sh, fx.l.ncurves);
        int seen = 0;
        for (size_t i = 0; i < fx.l.ncurves; i++) {
            const ism_sing_curve *c = &fx.l.curves[i];
            axis_part a = axis_summary(c);
            cr_assert_eq(c->kind, ISM_CURVE_DOUBLE, "shift %g: curve %zu", sh, i);
            cr_assert(ends_are(c, ISM_END_TRIPLE, ISM_END_BOX), "shift %g: curve %zu", sh, i);
            cr_assert_eq(end_point_of(c, ISM_END_TRIPLE), tp);
            cr_assert_leq(a.off, tol, "shift %g: curve %zu %g off its axis", sh, i, a.off);
            assert_box_end(&fx, c);
            seen |= 1 << (2 * a.axis + (a.sign > 0));
        }
        cr_assert_eq(seen, 63, "shift %g: half-axes covered %#x", sh, seen);
        assert_boxes_used(&fx);
        assert_all_steps(&fx);
        teardown(&fx);
    }
}

/* ---- three spheres f = g₁g₂g₃ (centres cᵢ, radii rᵢ, in general position): each pair crosses
 * in a circle (a double curve: there f is a non-zero multiple of gᵢgⱼ); the three circles
 * pass through the two points common to all three spheres, where the Hessian vanishes (it is
 * a sum of terms each with a factor g) — two triple points, six branches each: six arcs. */

typedef struct sphere3 { double c[3], r; } sphere3;
static const sphere3 SPHERES[3] = {
    {{0.5, 0.1, 0.0}, 1.0}, {{-0.3, 0.4, 0.1}, 0.9}, {{-0.2, -0.45, -0.05}, 1.1}};

typedef struct circle3 { double o[3], n[3], r; } circle3;

/* The circle where spheres i and j cross: centre, unit normal, radius. */
static circle3 circle_of(int i, int j)
{
    const sphere3 *a = &SPHERES[i], *b = &SPHERES[j];
    double d[3] = {b->c[0] - a->c[0], b->c[1] - a->c[1], b->c[2] - a->c[2]};
    double len = hypot(d[0], hypot(d[1], d[2]));
    double h = (len * len + a->r * a->r - b->r * b->r) / (2 * len);
    circle3 c;
    for (int k = 0; k < 3; k++) {
        c.n[k] = d[k] / len;
        c.o[k] = a->c[k] + h * c.n[k];
    }
    c.r = sqrt(a->r * a->r - h * h);
    return c;
}

static double circle_dist(const circle3 *c, const double p[3])
{
    double w[3] = {p[0] - c->o[0], p[1] - c->o[1], p[2] - c->o[2]};
    double along = w[0] * c->n[0] + w[1] * c->n[1] + w[2] * c->n[2];
    double radial = sqrt(fmax(0, w[0] * w[0] + w[1] * w[1] + w[2] * w[2] - along * along));
    return hypot(along, radial - c->r);
}

/* The two points on all three spheres: on the line where the radical planes of (1, 2) and
 * (1, 3) meet, at distance r₁ from c₁. */
static void triple_points(double out[2][3])
{
    double A[3][3], k[3];
    for (int j = 1; j < 3; j++) {
        const double *ci = SPHERES[0].c, *cj = SPHERES[j].c;
        k[j - 1] = SPHERES[0].r * SPHERES[0].r - SPHERES[j].r * SPHERES[j].r;
        for (int m = 0; m < 3; m++) {
            A[j - 1][m] = 2 * (cj[m] - ci[m]);
            k[j - 1] += cj[m] * cj[m] - ci[m] * ci[m];
        }
    }
    /* the line's direction, and its point where m·p = 0 (Cramer's rule) */
    double *u = A[0], *v = A[1];
    double m[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    for (int c = 0; c < 3; c++)
        A[2][c] = m[c];
    k[2] = 0;
    double det = A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) -
                 A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
                 A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
    double p0[3];
    for (int c = 0; c < 3; c++) {
        double B[3][3];
        memcpy(B, A, sizeof B);
        for (int r = 0; r < 3; r++)
            B[r][c] = k[r];
        p0[c] = (B[0][0] * (B[1][1] * B[2][2] - B[1][2] * B[2][1]) -
                 B[0][1] * (B[1][0] * B[2][2] - B[1][2] * B[2][0]) +
                 B[0][2] * (B[1][0] * B[2][1] - B[1][1] * B[2][0])) / det;
    }
    double ml = hypot(m[0], hypot(m[1], m[2])), w[3], b = 0, cc = -SPHERES[0].r * SPHERES[0].r;
    for (int c = 0; c < 3; c++) {
        m[c] /= ml;
        w[c] = p0[c] - SPHERES[0].c[c];
        b += 2 * w[c] * m[c];
        cc += w[c] * w[c];
    }
    for (int s = 0; s < 2; s++) {
        double t = (-b + (s ? 1 : -1) * sqrt(b * b - 4 * cc)) / 2;
        for (int c = 0; c < 3; c++)
            out[s][c] = p0[c] + t * m[c];
    }
}

static void seed_circle(const void *ctx, double s, double p[3])
{
    const circle3 *c = ctx;
    /* e: a unit vector normal to n (n × the axis least along n), f = n × e */
    int a = fabs(c->n[0]) < fabs(c->n[1]) ? (fabs(c->n[0]) < fabs(c->n[2]) ? 0 : 2)
                                          : (fabs(c->n[1]) < fabs(c->n[2]) ? 1 : 2);
    double ax[3] = {a == 0, a == 1, a == 2}, e[3], f[3];
    e[0] = c->n[1] * ax[2] - c->n[2] * ax[1];
    e[1] = c->n[2] * ax[0] - c->n[0] * ax[2];
    e[2] = c->n[0] * ax[1] - c->n[1] * ax[0];
    double l = hypot(e[0], hypot(e[1], e[2]));
    for (int k = 0; k < 3; k++)
        e[k] /= l;
    f[0] = c->n[1] * e[2] - c->n[2] * e[1];
    f[1] = c->n[2] * e[0] - c->n[0] * e[2];
    f[2] = c->n[0] * e[1] - c->n[1] * e[0];
    for (int k = 0; k < 3; k++)
        p[k] = c->o[k] + c->r * (cos(s) * e[k] + sin(s) * f[k]);
}

Test(singular_curves, three_spheres_two_triple_points_six_arcs)
{
    static const double box[6] = {-2, -2, -2, 2, 2, 2};
    char expr[512];
    size_t len = 0;
    for (int i = 0; i < 3; i++)
        len += (size_t)snprintf(expr + len, sizeof expr - len, "%s((x - %.17g)^2 + (y - %.17g)^2 + (z - %.17g)^2 - %.17g)",
                                i ? "*" : "", SPHERES[i].c[0], SPHERES[i].c[1], SPHERES[i].c[2],
                                SPHERES[i].r * SPHERES[i].r);
    double tp[2][3];
    triple_points(tp);
    circle3 circles[3] = {circle_of(0, 1), circle_of(0, 2), circle_of(1, 2)};
    for (int s = 0; s < NSHIFTS; s++) {
        fixture fx;
        double sh = setup(&fx, expr, box, s);
        fx.thick = true; /* every cell next to the circles too, as an interval search would */
        for (int c = 0; c < 3; c++)
            cover(&fx, seed_circle, &circles[c], 0, 2 * PI, circles[c].r);
        run(&fx);
        double tol = ON_LOCUS * fx.diag;
        cr_assert_eq(fx.l.npoints, 2, "shift %g: %zu points", sh, fx.l.npoints);
        int t0 = point_at(&fx, ISM_SING_TRIPLE, tp[0], tol), t1 = point_at(&fx, ISM_SING_TRIPLE, tp[1], tol);
        cr_assert(t0 >= 0 && t1 >= 0, "shift %g: triple points at %g %g %g and %g %g %g?", sh,
                  tp[0][0], tp[0][1], tp[0][2], tp[1][0], tp[1][1], tp[1][2]);
        cr_assert_eq(fx.l.ncurves, 6, "shift %g: %zu curves", sh, fx.l.ncurves);
        int arcs[3] = {0, 0, 0};
        for (size_t i = 0; i < fx.l.ncurves; i++) {
            const ism_sing_curve *c = &fx.l.curves[i];
            cr_assert_eq(c->kind, ISM_CURVE_DOUBLE, "shift %g: curve %zu", sh, i);
            cr_assert(ends_are(c, ISM_END_TRIPLE, ISM_END_TRIPLE), "shift %g: curve %zu", sh, i);
            cr_assert_neq(c->end_point[0], c->end_point[1], "shift %g: curve %zu", sh, i);
            int best = 0;
            double err[3];
            for (int k = 0; k < 3; k++) {
                err[k] = 0;
                for (size_t j = 0; j < c->n; j++)
                    err[k] = fmax(err[k], circle_dist(&circles[k], c->xyz + 3 * j));
                if (err[k] < err[best])
                    best = k;
            }
            cr_assert_leq(err[best], tol, "shift %g: curve %zu %g off its circle", sh, i, err[best]);
            arcs[best]++;
        }
        cr_assert(arcs[0] == 2 && arcs[1] == 2 && arcs[2] == 2, "shift %g: arcs %d %d %d", sh,
                  arcs[0], arcs[1], arcs[2]);
        assert_boxes_used(&fx);
        assert_all_steps(&fx);
        teardown(&fx);
    }
}

/* The same in the octant [0, 1]³: the axes now run along the box's edges (in two faces each),
 * which rounding puts a hair outside; three branches meet at the corner. Deliberately
 * lattice-aligned: that is the case. */
Test(singular_curves, xyz_axes_along_the_edges_of_the_box)
{
    static const double box[6] = {0, 0, 0, 1, 1, 1};
    static const double origin[3] = {0, 0, 0};
    fixture fx;
    setup(&fx, "x*y*z", box, 0);
    cover_axes(&fx, 2);
    run(&fx);
    double tol = ON_LOCUS * fx.diag;
    cr_assert_eq(fx.l.npoints, 1, "%zu points", fx.l.npoints);
    cr_assert_eq(point_at(&fx, ISM_SING_TRIPLE, origin, tol), 0);
    cr_assert_eq(fx.l.ncurves, 3, "%zu curves", fx.l.ncurves);
    int seen = 0;
    for (size_t i = 0; i < 3; i++) {
        const ism_sing_curve *c = &fx.l.curves[i];
        axis_part a = axis_summary(c);
        cr_assert(c->kind == ISM_CURVE_DOUBLE && ends_are(c, ISM_END_TRIPLE, ISM_END_BOX));
        cr_assert_leq(a.off, tol);
        cr_assert_leq(fabs(a.lo), tol);
        cr_assert_eq(a.hi, 1.0);
        seen |= 1 << a.axis;
    }
    cr_assert_eq(seen, 7);
    assert_boxes_used(&fx);
    assert_all_steps(&fx);
    teardown(&fx);
}

/* Seeds the cells along the lines through 0 in the directions dirs[k] (unit), |s| ≤ reach. */
static void cover_lines(fixture *fx, const double dirs[3][3], double reach)
{
    for (int k = 0; k < 3; k++)
        for (double s = -reach; s <= reach; s += fx->cell / 8) {
            double p[3] = {s * dirs[k][0], s * dirs[k][1], s * dirs[k][2]};
            seed_cell(fx, p);
        }
}

/* Whiskers meeting where the Hessian keeps rank 1. f = L² + (A·B)² with the plane L = z − 0.3x
 * + 0.2y = 0 and the planes A = x + 0.1y, B = y − 0.2x + 0.1z: f = 0 on the two lines L = A = 0
 * (direction (−0.1, 1, −0.23)) and L = B = 0 (direction (1, 0.17/0.98, 0.3 − 0.2·0.17/0.98)),
 * whiskers (f ≥ 0). On one line the Hessian across is 2∇L∇Lᵀ + 2B²∇A∇Aᵀ: its second
 * eigenvalue vanishes like the square of the distance to 0, where the other line crosses
 * (four branches: a triple point, though the Hessian has rank 1 there). Then z² + y²(x² + y²):
 * the x axis only (∇f = (2xy², 2x²y + 4y³, 2z)), the Hessian across diag(2x², 2) degenerate
 * at 0 with one branch through: a degenerate point splitting the whisker, not a triple point. */
Test(singular_curves, whiskers_meeting_where_the_hessian_has_rank_one)
{
    static const double box[6] = {-1, -1, -1, 1, 1, 1};
    static const double origin[3] = {0, 0, 0};
    double m = 0.17 / 0.98, dirs[3][3] = {{-0.1, 1, -0.23}, {1, m, 0.3 - 0.2 * m}, {0, 0, 0}};
    for (int k = 0; k < 2; k++) {
        double l = hypot(dirs[k][0], hypot(dirs[k][1], dirs[k][2]));
        for (int c = 0; c < 3; c++)
            dirs[k][c] /= l;
    }
    dirs[2][0] = dirs[0][1] * dirs[1][2] - dirs[0][2] * dirs[1][1]; /* a third direction, */
    dirs[2][1] = dirs[0][2] * dirs[1][0] - dirs[0][0] * dirs[1][2]; /* on no curve */
    dirs[2][2] = dirs[0][0] * dirs[1][1] - dirs[0][1] * dirs[1][0];
    for (int s = 0; s < NSHIFTS; s++) {
        fixture fx;
        double sh = setup(&fx, "(z - 0.3*x + 0.2*y)^2 + ((x + 0.1*y)*(y - 0.2*x + 0.1*z))^2", box, s);
        double two[3][3];
        memcpy(two, dirs, sizeof two);
        memcpy(two[2], dirs[0], sizeof two[2]); /* seed the two lines only */
        cover_lines(&fx, two, 2);
        run(&fx);
        double tol = ON_LOCUS * fx.diag;
        cr_assert_eq(fx.l.npoints, 1, "shift %g: %zu points", sh, fx.l.npoints);
        int tp = point_at(&fx, ISM_SING_TRIPLE, origin, tol);
        cr_assert_eq(tp, 0, "shift %g: %s at %g %g %g", sh, ism_sing_type_name(fx.l.points[0].type),
                     fx.l.points[0].p[0], fx.l.points[0].p[1], fx.l.points[0].p[2]);
        cr_assert_eq(fx.l.ncurves, 4, "shift %g: %zu curves", sh, fx.l.ncurves);
        int seen = 0;
        for (size_t i = 0; i < 4; i++) {
            const ism_sing_curve *c = &fx.l.curves[i];
            axis_part a = line_summary(c, dirs);
            cr_assert(c->kind == ISM_CURVE_WHISKER && ends_are(c, ISM_END_TRIPLE, ISM_END_BOX),
                      "shift %g: curve %zu", sh, i);
            cr_assert_lt(a.axis, 2);
            cr_assert_leq(a.off, tol, "shift %g: curve %zu %g off its line", sh, i, a.off);
            seen |= 1 << (2 * a.axis + (a.sign > 0));
        }
        cr_assert_eq(seen, 15, "shift %g", sh);
        assert_boxes_used(&fx);
        assert_all_steps(&fx);
        teardown(&fx);

        sh = setup(&fx, "z^2 + y^2*(x^2 + y^2)", box, s);
        cover(&fx, x_axis, NULL, -2, 2, 1);
        run(&fx);
        cr_assert_eq(fx.l.npoints, 1, "shift %g: %zu points", sh, fx.l.npoints);
        cr_assert_eq(point_at(&fx, ISM_SING_DEGENERATE, origin, tol), 0, "shift %g", sh);
        cr_assert_eq(fx.l.ncurves, 2, "shift %g: %zu curves", sh, fx.l.ncurves);
        for (size_t i = 0; i < 2; i++) {
            const ism_sing_curve *c = &fx.l.curves[i];
            cr_assert(c->kind == ISM_CURVE_WHISKER && ends_are(c, ISM_END_POINT, ISM_END_BOX));
            cr_assert_leq(axis_summary(c).off, tol);
        }
        teardown(&fx);
    }
}

/* Steiner's Roman surface x²y² + y²z² + z²x² + xyz. On the x axis the Hessian across is
 * [[2x², x], [x, 2x²]]: eigenvalues 2x² ± x, indefinite for |x| < 1/2 (a double line), definite
 * beyond (a whisker), one eigenvalue crossing 0 at x = ±1/2 (pinch points); it vanishes at
 * the origin, where the three axes meet (a triple point). Likewise on y and z. Here in the
 * coordinates u = R p, so its lines run along the rows of R. */
static void check_steiner(const double R[3][3], bool thick)
{
    static const double box[6] = {-1, -1, -1, 1, 1, 1};
    static const double origin[3] = {0, 0, 0};
    char defs[3][200];
    ism_let lets[3];
    for (int k = 0; k < 3; k++) {
        snprintf(defs[k], sizeof defs[k], "%.17g*x + %.17g*y + %.17g*z", R[k][0], R[k][1], R[k][2]);
        lets[k] = (ism_let){k == 0 ? "u" : k == 1 ? "v" : "w", defs[k]};
    }
    for (int s = 0; s < NSHIFTS; s++) {
        fixture fx;
        double sh = setup_lets(&fx, "u^2*v^2 + v^2*w^2 + w^2*u^2 + u*v*w", lets, 3, box, s);
        fx.thick = thick;
        cover_lines(&fx, R, 2);
        run(&fx);
        double tol = ON_LOCUS * fx.diag;
        cr_assert_eq(count_points(&fx, ISM_SING_TRIPLE), 1, "shift %g", sh);
        cr_assert_eq(count_points(&fx, ISM_SING_PINCH), 6, "shift %g", sh);
        cr_assert_eq(fx.l.npoints, 7, "shift %g: %zu points", sh, fx.l.npoints);
        int tp = point_at(&fx, ISM_SING_TRIPLE, origin, tol);
        cr_assert_geq(tp, 0, "shift %g: triple point off the origin", sh);
        for (int k = 0; k < 6; k++) {
            double h = k % 2 ? 0.5 : -0.5, p[3] = {h * R[k / 2][0], h * R[k / 2][1], h * R[k / 2][2]};
            cr_assert_geq(point_at(&fx, ISM_SING_PINCH, p, tol), 0, "shift %g: no pinch at %g %g %g",
                          sh, p[0], p[1], p[2]);
        }
        cr_assert_eq(fx.l.ncurves, 12, "shift %g: %zu curves", sh, fx.l.ncurves);
        int seen = 0;
        for (size_t i = 0; i < fx.l.ncurves; i++) {
            const ism_sing_curve *c = &fx.l.curves[i];
            axis_part a = line_summary(c, R);
            double near = a.sign > 0 ? a.lo : -a.hi, far = a.sign > 0 ? a.hi : -a.lo;
            cr_assert_leq(a.off, tol, "shift %g: curve %zu %g off its line", sh, i, a.off);
            if (c->kind == ISM_CURVE_DOUBLE) {
                cr_assert(ends_are(c, ISM_END_TRIPLE, ISM_END_PINCH), "shift %g: curve %zu", sh, i);
                cr_assert_eq(end_point_of(c, ISM_END_TRIPLE), tp);
                cr_assert_leq(fabs(near), tol, "shift %g: curve %zu", sh, i);
                cr_assert_leq(fabs(far - 0.5), tol, "shift %g: curve %zu reaches %.12g", sh, i, far);
            } else {
                cr_assert(ends_are(c, ISM_END_PINCH, ISM_END_BOX), "shift %g: curve %zu", sh, i);
                cr_assert_leq(fabs(near - 0.5), tol, "shift %g: whisker %zu from %.12g", sh, i, near);
                assert_box_end(&fx, c);
            }
            seen |= 1 << (4 * a.axis + 2 * (c->kind == ISM_CURVE_DOUBLE) + (a.sign > 0));
        }
        cr_assert_eq(seen, 4095, "shift %g: parts covered %#x", sh, seen);
        assert_boxes_used(&fx);
        assert_all_steps(&fx);
        teardown(&fx);
    }
}

Test(singular_curves, steiner_axes_pinch_points_and_triple_point)
{
    check_steiner(AXES, false);
}

/* The same surface turned by 0.6 rad about (1, 2, 2)/3 (Rodrigues): lines off every lattice
 * direction, leaving the box through faces at oblique angles; seeded thick (every cell next
 * to the curve too), as an interval search would. */
Test(singular_curves, steiner_turned_off_the_lattice_directions)
{
    const double k[3] = {1.0 / 3, 2.0 / 3, 2.0 / 3}, c = cos(0.6), s = sin(0.6);
    double R[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            static const int eps[3][3] = {{0, 3, -2}, {-3, 0, 1}, {2, -1, 0}}; /* ±(1 + index) */
            int e = eps[i][j];
            double cross = e == 0 ? 0 : (e > 0 ? 1 : -1) * k[abs(e) - 1]; /* [k]× */
            R[i][j] = (i == j ? c : 0) + (1 - c) * k[i] * k[j] - s * cross;
        }
    check_steiner(R, true);
}

/* An umbrella's points: one pinch point, at the origin, and two curves. */
static void assert_umbrella_points(const fixture *fx, double sh)
{
    static const double origin[3] = {0, 0, 0};
    cr_assert_eq(fx->l.npoints, 1, "shift %g: %zu points", sh, fx->l.npoints);
    cr_assert_eq(point_at(fx, ISM_SING_PINCH, origin, ON_LOCUS * fx->diag), 0,
                 "shift %g: pinch at %g %g %g", sh, fx->l.points[0].p[0], fx->l.points[0].p[1],
                 fx->l.points[0].p[2]);
    cr_assert_eq(fx->l.ncurves, 2, "shift %g: %zu curves", sh, fx->l.ncurves);
}

/* Whitney's umbrella x² − y²z. On the z axis ∇f = 0 and the Hessian across is
 * diag(2, −2z): indefinite for z > 0 (the two sheets y = ±x/√z cross: a double half-line),
 * definite for z < 0 (the handle: a whisker), the crossing at the origin a pinch point. */
Test(singular_curves, whitney_umbrella_pinch_double_and_whisker)
{
    static const double box[6] = {-1, -1, -1, 1, 1, 1};
    for (int s = 0; s < NSHIFTS; s++) {
        fixture fx;
        double sh = setup(&fx, "x^2 - y^2*z", box, s);
        cover(&fx, z_axis, NULL, -2, 2, 1);
        run(&fx);
        double tol = ON_LOCUS * fx.diag;
        assert_umbrella_points(&fx, sh);
        for (size_t i = 0; i < 2; i++) {
            const ism_sing_curve *c = &fx.l.curves[i];
            axis_part a = axis_summary(c);
            cr_assert_eq(a.axis, 2);
            cr_assert_leq(a.off, tol);
            cr_assert(ends_are(c, ISM_END_PINCH, ISM_END_BOX), "shift %g: curve %zu", sh, i);
            cr_assert_eq(c->kind, a.sign > 0 ? ISM_CURVE_DOUBLE : ISM_CURVE_WHISKER,
                         "shift %g: the %s half is a %s", sh, a.sign > 0 ? "upper" : "lower",
                         ism_curve_kind_name(c->kind));
            cr_assert_leq(a.sign > 0 ? fabs(a.lo) : fabs(a.hi), tol);
            assert_box_end(&fx, c);
        }
        assert_boxes_used(&fx);
        assert_all_steps(&fx);
        teardown(&fx);
    }
}

/* The umbrella bent: (x − z²)² − y²z is Whitney's X² − Y²Z in the coordinates X = x − z²,
 * Y = y, Z = z (a diffeomorphism), so its singular curve is the parabola x = z², y = 0: a
 * double curve for z > 0, a whisker for z < 0, the pinch point at the origin. */
static void parabola(const void *ctx, double s, double p[3]) { (void)ctx, p[0] = s * s, p[1] = 0, p[2] = s; }

/* An upper bound of the distance to the parabola: to its point at the same z. */
static double parabola_dist(const double p[3]) { return hypot(p[0] - p[2] * p[2], p[1]); }

Test(singular_curves, bent_umbrella_pinch_on_a_parabola)
{
    static const double box[6] = {-1.2, -1.2, -1.2, 1.2, 1.2, 1.2};
    for (int s = 0; s < NSHIFTS; s++) {
        fixture fx;
        double sh = setup(&fx, "(x - z^2)^2 - y^2*z", box, s);
        cover(&fx, parabola, NULL, -1.3, 1.3, 2.7);
        run(&fx);
        double tol = ON_LOCUS * fx.diag;
        assert_umbrella_points(&fx, sh);
        for (size_t i = 0; i < 2; i++) {
            const ism_sing_curve *c = &fx.l.curves[i];
            double vert, mid, zsum = 0;
            curve_error(c, parabola_dist, &vert, &mid);
            cr_assert_leq(vert, tol, "shift %g: vertex %g off the parabola", sh, vert);
            /* sagitta of a chord ≤ 0.6 cell where the curvature is ≤ 2 */
            cr_assert_leq(mid, 2 * 0.36 * fx.cell * fx.cell / 8 + tol, "shift %g: %g", sh, mid);
            cr_assert(ends_are(c, ISM_END_PINCH, ISM_END_BOX), "shift %g: curve %zu", sh, i);
            const double *e = end_vertex(c, ISM_END_BOX);
            cr_assert_eq(e[0], fx.o.box[3], "shift %g: leaves at x = %.17g", sh, e[0]);
            for (size_t j = 0; j < c->n; j++)
                zsum += c->xyz[3 * j + 2];
            cr_assert_eq(c->kind, zsum > 0 ? ISM_CURVE_DOUBLE : ISM_CURVE_WHISKER, "shift %g", sh);
        }
        cr_assert_neq(fx.l.curves[0].kind, fx.l.curves[1].kind);
        assert_boxes_used(&fx);
        assert_all_steps(&fx);
        teardown(&fx);
    }
}

/* The cross-cap 4x²(x² + y² + z² + z) + y²(y² + z² − 1). On the z axis ∇f = 0 and the
 * Hessian is diag(8(z² + z), 2(z² − 1), 0): its determinant across, 16 z (z + 1)² (z − 1), is
 * negative for 0 < z < 1 (double segment), positive elsewhere (whisker), changes sign at z = 0
 * and z = 1 (pinch points: one eigenvalue crosses 0, the other is −2 resp. 16), and vanishes
 * without changing sign at z = −1, where the whole Hessian vanishes (the bottom of the cap
 * touches the whisker there: a degenerate point, not a triple point — one branch only). */
Test(singular_curves, cross_cap_double_segment_between_two_pinch_points)
{
    static const double box[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
    static const double pinch0[3] = {0, 0, 0}, pinch1[3] = {0, 0, 1}, bottom[3] = {0, 0, -1};
    static const char expr[] = "4*x^2*(x^2 + y^2 + z^2 + z) + y^2*(y^2 + z^2 - 1)";
    for (int s = 0; s < NSHIFTS; s++) {
        fixture fx;
        double sh = setup(&fx, expr, box, s);
        fx.thick = true; /* every cell next to the axis too, as an interval search would */
        cover(&fx, z_axis, NULL, -2, 2, 1);
        run(&fx);
        double tol = ON_LOCUS * fx.diag;
        cr_assert_eq(fx.l.npoints, 3, "shift %g: %zu points", sh, fx.l.npoints);
        int p0 = point_at(&fx, ISM_SING_PINCH, pinch0, tol);
        int p1 = point_at(&fx, ISM_SING_PINCH, pinch1, tol);
        int pd = point_at(&fx, ISM_SING_DEGENERATE, bottom, tol);
        cr_assert(p0 >= 0 && p1 >= 0 && pd >= 0, "shift %g: points %d %d %d", sh, p0, p1, pd);
        cr_assert_eq(fx.l.ncurves, 4, "shift %g: %zu curves", sh, fx.l.ncurves);
        /* expected parts along z, bottom to top */
        static const struct { double lo, hi; int kind, end0, end1; } parts[4] = {
            {-1.5, -1, ISM_CURVE_WHISKER, ISM_END_BOX, ISM_END_POINT},
            {-1, 0, ISM_CURVE_WHISKER, ISM_END_POINT, ISM_END_PINCH},
            {0, 1, ISM_CURVE_DOUBLE, ISM_END_PINCH, ISM_END_PINCH},
            {1, 1.5, ISM_CURVE_WHISKER, ISM_END_PINCH, ISM_END_BOX},
        };
        int seen = 0;
        for (size_t i = 0; i < 4; i++) {
            const ism_sing_curve *c = &fx.l.curves[i];
            axis_part a = axis_summary(c);
            cr_assert_eq(a.axis, 2);
            cr_assert_leq(a.off, tol);
            int k = 0;
            while (k < 3 && a.hi > parts[k].hi + 0.25)
                k++;
            double lo = parts[k].lo == -1.5 ? fx.o.box[2] : parts[k].lo;
            double hi = parts[k].hi == 1.5 ? fx.o.box[5] : parts[k].hi;
            cr_assert_leq(fabs(a.lo - lo), tol, "shift %g: part %d from %.12g", sh, k, a.lo);
            cr_assert_leq(fabs(a.hi - hi), tol, "shift %g: part %d to %.12g", sh, k, a.hi);
            cr_assert_eq(c->kind, parts[k].kind, "shift %g: part %d", sh, k);
            cr_assert(ends_are(c, parts[k].end0, parts[k].end1), "shift %g: part %d ends %d %d", sh,
                      k, c->end_type[0], c->end_type[1]);
            seen |= 1 << k;
        }
        cr_assert_eq(seen, 15, "shift %g", sh);
        assert_boxes_used(&fx);
        assert_all_steps(&fx);
        teardown(&fx);
    }
}

/* Seeds that lead to no curve of the zero set give none, and stay unexplained: a circle of
 * critical points at level f = 0.01 (no point of f = 0 there), a sphere counted twice
 * ((x² + y² + z² − 0.5)²: ∇f = 0 on a whole sheet, Hessian of rank 1 — seeded here as if
 * rank 2), and an isolated cusp x² + z² − y³ (∇f = 0 only at the origin). */
static void sphere_circle(const void *ctx, double s, double p[3])
{
    (void)ctx;
    double r = sqrt(0.5);
    p[0] = r * cos(s), p[1] = r * sin(s), p[2] = 0;
}

Test(singular_curves, no_curve_where_there_is_none)
{
    static const double box[6] = {-1, -1, -1, 1, 1, 1};
    static const struct { const char *expr; curve_fn g; double s0, s1, speed; } cases[] = {
        {"(x^2 + y^2 - 0.25)^2 + z^2 + 0.01", whisker_circle, 0, 2 * PI, 0.5},
        {"(x^2 + y^2 + z^2 - 0.5)^2", sphere_circle, 0, 2 * PI, 0.71},
        {"x^2 + z^2 - y^3", z_axis, -0.01, 0.01, 1},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        for (int s = 0; s < NSHIFTS; s++) {
            fixture fx;
            double sh = setup(&fx, cases[i].expr, box, s);
            cover(&fx, cases[i].g, NULL, cases[i].s0, cases[i].s1, cases[i].speed);
            size_t seeds = 0;
            for (size_t b = 0; b < fx.l.nboxes; b++)
                if (fx.l.boxes[b].flags & ISM_LBOX_PROJECTED) {
                    fx.l.boxes[b].rank = 2; /* as a search with a loose rank test would */
                    seeds++;
                }
            cr_assert_gt(seeds, 0, "%s: no seeds", cases[i].expr);
            run(&fx);
            cr_assert_eq(fx.l.ncurves, 0, "%s, shift %g: %zu curves", cases[i].expr, sh,
                         fx.l.ncurves);
            cr_assert_eq(fx.l.npoints, 0, "%s, shift %g: %zu points", cases[i].expr, sh,
                         fx.l.npoints);
            for (size_t b = 0; b < fx.l.nboxes; b++)
                cr_assert_not(fx.l.boxes[b].flags & ISM_LBOX_USED, "%s: box %zu", cases[i].expr, b);
            teardown(&fx);
        }
}

/* The same structures from the interval search's own candidate boxes (ism_locus_find) instead
 * of the boxes made here: every rank-2 box it leaves is explained, and the counts are the
 * closed forms' (derived in the tests above). */
Test(singular_curves, from_the_interval_search)
{
    static const struct {
        const char *expr;
        double lo, hi;
        size_t doubles, whiskers, pinch, triple, degenerate;
    } cases[] = {
        {"x^2 - y^2*z", -1, 1, 1, 1, 1, 0, 0},
        {"4*x^2*(x^2 + y^2 + z^2 + z) + y^2*(y^2 + z^2 - 1)", -1.5, 1.5, 1, 3, 2, 0, 1},
        {"x*y*z", -1, 1, 6, 0, 0, 1, 0},
        {"(x^2 + y^2 - 0.25)^2 + z^2", -1, 1, 0, 1, 0, 0, 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        for (int s = 0; s < NSHIFTS; s++) {
            fixture fx;
            const double box[6] = {cases[i].lo, cases[i].lo, cases[i].lo, cases[i].hi, cases[i].hi, cases[i].hi};
            double sh = setup(&fx, cases[i].expr, box, s);
            ism_error err;
            cr_assert(ism_locus_find(fx.t, &fx.o, &fx.l, &err), "%s", err.message);
            run(&fx);
            size_t kinds[2] = {0, 0};
            for (size_t c = 0; c < fx.l.ncurves; c++)
                kinds[fx.l.curves[c].kind]++;
            cr_assert(kinds[ISM_CURVE_DOUBLE] == cases[i].doubles &&
                          kinds[ISM_CURVE_WHISKER] == cases[i].whiskers,
                      "%s, shift %g: %zu double, %zu whisker curves", cases[i].expr, sh,
                      kinds[ISM_CURVE_DOUBLE], kinds[ISM_CURVE_WHISKER]);
            cr_assert(count_points(&fx, ISM_SING_PINCH) == cases[i].pinch &&
                          count_points(&fx, ISM_SING_TRIPLE) == cases[i].triple &&
                          count_points(&fx, ISM_SING_DEGENERATE) == cases[i].degenerate &&
                          fx.l.npoints == cases[i].pinch + cases[i].triple + cases[i].degenerate,
                      "%s, shift %g: %zu points", cases[i].expr, sh, fx.l.npoints);
            assert_boxes_used(&fx);
            assert_all_steps(&fx);
            teardown(&fx);
        }
}

/* A cancel flag or a past deadline stops the stage: incomplete, with a reason. */
Test(singular_curves, cancel_and_deadline_leave_it_incomplete)
{
    static const double box[6] = {-1, -1, -1, 1, 1, 1};
    for (int which = 0; which < 2; which++) {
        fixture fx;
        setup(&fx, "x*y*z", box, 0);
        cover_axes(&fx, 2);
        volatile int cancel = 1;
        if (which == 0)
            fx.o.cancel = &cancel;
        else
            fx.o.deadline_ms = 1e-3; /* long past on the monotonic clock */
        ism_error err;
        cr_assert(ism_sing_trace_curves(fx.t, &fx.o, &fx.l, &err));
        cr_assert(fx.l.incomplete);
        cr_assert_not_null(strstr(fx.l.incomplete_why, which == 0 ? "cancel" : "deadline"), "%s",
                           fx.l.incomplete_why);
        teardown(&fx);
    }
}
