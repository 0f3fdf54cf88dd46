/* test_curves_cells.c — the cut's culling (core/curves/cut_cells.c: per function only the
 * grid cells whose interval of g may hold 0, and the ring round them) checked by a second
 * method. The ellipsoid x²/4 + y²/2.25 + z² = 1 is cut by 16 seeded planes (half given as
 * planes, half as level tapes of a linear expression: the two interval paths), in the lattice
 * box and boxes shifted 1e-3 and √2 − 1 of a finest cell off it:
 *   - counts from closed forms: two plane sections meet where the line of the two planes
 *     meets the ellipsoid (a quadratic: 0 or 2 points); V = the crossings plus one point on
 *     each section meeting none, E = the vertices on each section (1 for a lone loop), and
 *     on the sphere V − E + F = 1 + C (C: the sections' connected groups);
 *   - every crossing vertex within 1e-9 × diagonal of a closed-form crossing point;
 *   - no triangle straddles a plane (g at its corners, closed form, both signs beyond
 *     0.01 of a finest cell): a cell wrongly ruled out would leave its triangles uncut;
 *   - the faces found again by a flood fill of the triangles across mesh edges that are no
 *     curve edge by the closed forms (not both ends on one plane): the same partition of the
 *     triangles as the arrangement's. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "poly_fixture.h"
#include "core/curves/curves.h"

#define NPLANES 16
#define ON_REL 1e-9      /* the precision for curve points (× diagonal) */
/* The closed-form counts need a generic arrangement: no pair of sections nearly tangent (a
 * pair's line misses the ellipsoid with a discriminant at least this × its scale, or meets
 * it in two points at least SEPARATE_CELLS finest cells apart) and no third plane within
 * SEPARATE_CELLS of a crossing (no triple point). With 16 planes, crossings closer to a
 * third plane than a cell are the rule (about a hundred here): the cut resolves them. */
#define DISC_MARGIN 1e-3
/* A triangle the cut missed has corners on both sides of the plane by about its size. A
 * vertex of a later curve is put on its curve in the plane through the edge it splits and
 * ∇f (cut.c), so it stays beside the edge; the surface there is off the flat triangles by up
 * to their sagitta L²κ/8 (L: the longest edge, κ: the ellipsoid's largest curvature, a/c² =
 * 2), so next to a crossing, where an earlier plane runs through the triangle's corner, the
 * vertex may lie across it by at most that. Measured: none in the lattice and 1e-3 boxes,
 * 1.4e-4 (0.0019 cell, 3 triangles at a near-triple point of three planes) 0.37 cell off it;
 * before the split point was kept beside its edge (minimum-norm Newton slid it along the
 * curve) 2.0e-5 (4) in the lattice box and 2.6e-4 (3) off it. */
#define KAPPA_MAX 2.0
#define SEPARATE_CELLS 0.01

static const double axes2[3] = {4, 2.25, 1}; /* the ellipsoid's squared half-axes */

typedef struct plane {
    double n[3], d;
} plane;

static double dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* A 64-bit LCG (Knuth's MMIX constants): the same planes everywhere. */
static double uniform(uint64_t *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*s >> 11) / 9007199254740992.0;
}

/* Random unit normals; offsets within 0.8 of the support function sqrt(nᵀA⁻¹n). */
static void make_planes(plane *pl)
{
    uint64_t s = 140;
    for (int i = 0; i < NPLANES; i++) {
        double n[3], l = 0;
        for (int k = 0; k < 3; k++) {
            n[k] = 2 * uniform(&s) - 1;
            l += n[k] * n[k];
        }
        double h = 0;
        for (int k = 0; k < 3; k++) {
            pl[i].n[k] = n[k] / sqrt(l);
            h += pl[i].n[k] * pl[i].n[k] * axes2[k];
        }
        pl[i].d = (1.6 * uniform(&s) - 0.8) * sqrt(h);
    }
}

/* The points where planes a and b meet the ellipsoid (0 or 2, into q); asserts genericity. */
static int crossings(const plane *a, const plane *b, double cell, double q[2][3])
{
    double u[3] = {a->n[1] * b->n[2] - a->n[2] * b->n[1], a->n[2] * b->n[0] - a->n[0] * b->n[2],
                   a->n[0] * b->n[1] - a->n[1] * b->n[0]};
    double nn = dot3(a->n, b->n), det = 1 - nn * nn; /* unit normals */
    cr_assert_gt(det, 1e-3, "two planes nearly parallel");
    double ca = (a->d - b->d * nn) / det, cb = (b->d - a->d * nn) / det, p0[3];
    for (int k = 0; k < 3; k++)
        p0[k] = ca * a->n[k] + cb * b->n[k];
    double qa = 0, qb = 0, qc = -1; /* (p0 + t u)ᵀ A (p0 + t u) = 1 */
    for (int k = 0; k < 3; k++) {
        qa += u[k] * u[k] / axes2[k];
        qb += 2 * p0[k] * u[k] / axes2[k];
        qc += p0[k] * p0[k] / axes2[k];
    }
    double disc = qb * qb - 4 * qa * qc;
    if (disc < 0) {
        cr_assert_gt(-disc, DISC_MARGIN * (qb * qb + fabs(4 * qa * qc)),
                     "a pair of sections nearly touching");
        return 0;
    }
    cr_assert_gt(sqrt(disc) / qa * sqrt(dot3(u, u)), SEPARATE_CELLS * cell,
                 "a pair of sections nearly tangent");
    for (int r = 0; r < 2; r++) {
        double t = (-qb + (r ? 1 : -1) * sqrt(disc)) / (2 * qa);
        for (int k = 0; k < 3; k++)
            q[r][k] = p0[k] + t * u[k];
    }
    return 2;
}

static uint32_t uf_find(uint32_t *p, uint32_t x)
{
    while (p[x] != x)
        x = p[x] = p[p[x]];
    return x;
}

typedef struct expect {
    size_t v, e, f;
    double pts[NPLANES * NPLANES][3];
    size_t npts;
} expect;

/* V, E, F of the arrangement from the closed forms, and the crossing points. */
static void expected(const plane *pl, double cell, expect *x)
{
    int on_curve[NPLANES] = {0};
    uint32_t par[NPLANES];
    memset(x, 0, sizeof *x);
    for (uint32_t i = 0; i < NPLANES; i++)
        par[i] = i;
    for (int i = 0; i < NPLANES; i++)
        for (int j = i + 1; j < NPLANES; j++) {
            double q[2][3];
            int n = crossings(&pl[i], &pl[j], cell, q);
            for (int r = 0; r < n; r++) {
                for (int k = 0; k < NPLANES; k++)
                    if (k != i && k != j)
                        cr_assert_gt(fabs(dot3(pl[k].n, q[r]) - pl[k].d), SEPARATE_CELLS * cell,
                                     "a third plane through a crossing");
                memcpy(x->pts[x->npts++], q[r], sizeof q[r]);
            }
            on_curve[i] += n;
            on_curve[j] += n;
            if (n)
                par[uf_find(par, (uint32_t)i)] = uf_find(par, (uint32_t)j);
        }
    size_t groups = 0;
    x->v = x->npts;
    for (int i = 0; i < NPLANES; i++) {
        groups += uf_find(par, (uint32_t)i) == (uint32_t)i;
        x->v += on_curve[i] == 0; /* a lone loop's one vertex */
        x->e += on_curve[i] ? (size_t)on_curve[i] : 1;
    }
    x->f = 1 + groups + x->e - x->v;
}

/* g_i at mesh vertex v, closed form. */
static double g_at(const ism_mesh *m, const plane *p, uint32_t v)
{
    return dot3(p->n, m->pos + 3 * (size_t)v) - p->d;
}

typedef struct edge_ref {
    uint64_t key;
    uint32_t tri; /* a triangle of the edge */
} edge_ref;

static int cmp_edge_ref(const void *a, const void *b)
{
    uint64_t x = ((const edge_ref *)a)->key, y = ((const edge_ref *)b)->key;
    return (x > y) - (x < y);
}

/* Whether mesh edge a-b separates: both ends on one of the planes. (Not also "the triangles'
 * off corners on opposite sides": next to a crossing a vertex of the later curve may lie a
 * little across the earlier plane — see KAPPA_MAX — and the triangle between it and the
 * earlier curve's edge is then folded over. An edge with both ends on a plane that is no cut
 * edge, a chord, would split a face in two here: the counts below say there is none.) */
static bool separates(const ism_mesh *m, const plane *pl, uint32_t a, uint32_t b, double tol)
{
    for (int i = 0; i < NPLANES; i++)
        if (fabs(g_at(m, &pl[i], a)) <= tol && fabs(g_at(m, &pl[i], b)) <= tol)
            return true;
    return false;
}

/* Flood fill of the triangles across edges that do not separate: the component of each
 * triangle into comp; returns the number of components. */
static size_t flood_faces(const ism_mesh *m, const plane *pl, double tol, uint32_t *comp)
{
    size_t n = 3 * m->ntris;
    edge_ref *r = malloc(n * sizeof *r);
    for (size_t t = 0; t < m->ntris; t++)
        for (int i = 0; i < 3; i++) {
            uint32_t a = m->tri[3 * t + i], b = m->tri[3 * t + (i + 1) % 3];
            uint64_t key = a < b ? ((uint64_t)a << 32) | b : ((uint64_t)b << 32) | a;
            r[3 * t + i] = (edge_ref){key, (uint32_t)t};
        }
    qsort(r, n, sizeof *r, cmp_edge_ref);
    uint32_t *par = malloc(m->ntris * sizeof *par);
    for (size_t t = 0; t < m->ntris; t++)
        par[t] = (uint32_t)t;
    for (size_t i = 0; i < n;) {
        size_t j = i;
        while (j < n && r[j].key == r[i].key)
            j++;
        cr_assert_eq(j - i, 2, "the ellipsoid's mesh is closed and manifold");
        uint32_t a = (uint32_t)(r[i].key >> 32), b = (uint32_t)r[i].key;
        if (!separates(m, pl, a, b, tol))
            par[uf_find(par, r[i].tri)] = uf_find(par, r[i + 1].tri);
        i = j;
    }
    size_t k = 0;
    uint32_t *id = malloc(m->ntris * sizeof *id);
    for (size_t t = 0; t < m->ntris; t++)
        id[t] = uf_find(par, (uint32_t)t) == t ? (uint32_t)k++ : UINT32_MAX;
    for (size_t t = 0; t < m->ntris; t++)
        comp[t] = id[uf_find(par, (uint32_t)t)];
    free(id);
    free(par);
    free(r);
    return k;
}

/* The two partitions of the triangles agree: each flood component lies in one face and each
 * face in one component. */
static void same_partition(const ism_arrangement *a, const uint32_t *comp, size_t ncomp,
                           size_t ntris)
{
    uint32_t *face_of = malloc(ncomp * sizeof *face_of), *comp_of = malloc(a->nfaces * sizeof *comp_of);
    memset(face_of, 0xff, ncomp * sizeof *face_of);
    memset(comp_of, 0xff, a->nfaces * sizeof *comp_of);
    for (size_t t = 0; t < ntris; t++) {
        uint32_t f = a->tri_face[t], c = comp[t];
        if (face_of[c] == UINT32_MAX)
            face_of[c] = f;
        if (comp_of[f] == UINT32_MAX)
            comp_of[f] = c;
        cr_assert_eq(face_of[c], f, "a flood-fill face spans arrangement faces");
        cr_assert_eq(comp_of[f], c, "an arrangement face spans flood-fill faces");
    }
    free(face_of);
    free(comp_of);
}

static void ellipsoid_planes(int which)
{
    static const pf_surface ellipsoid = {"x^2/4 + y^2/2.25 + z^2 - 1", NULL, 0, NULL, 0};
    const double base[6] = {-2.3, -1.8, -1.3, 2.3, 1.8, 1.3}, dir[3] = {1.0, 0.61, -0.83};
    int depth = 6;
    double cell = 4.6 / (1 << depth), box[6];
    double s = which == 0 ? 0 : which == 1 ? 1e-3 : PF_IRR * cell;
    for (int k = 0; k < 6; k++)
        box[k] = base[k] + s * dir[k % 3];
    double diag = sqrt(4.6 * 4.6 + 3.6 * 3.6 + 2.6 * 2.6), tol = ON_REL * diag;
    plane pl[NPLANES];
    make_planes(pl);
    expect *x = malloc(sizeof *x);
    expected(pl, cell, x);

    ism_tape *f = pf_compile(&ellipsoid);
    ism_mesh m; /* pf_run initialises it */
    ism_poly_stats st;
    pf_run(f, box, 3, depth, 1, &m, &st);
    cr_assert(ism_mesh_drop_loose(&m));
    ism_tape *lin[NPLANES] = {0};
    ism_cut_fn fns[NPLANES];
    for (int i = 0; i < NPLANES; i++) {
        if (i % 2) { /* a level of a tape: g's interval from the tape */
            char src[200];
            snprintf(src, sizeof src, "(%.17g)*x + (%.17g)*y + (%.17g)*z", pl[i].n[0], pl[i].n[1],
                     pl[i].n[2]);
            lin[i] = pf_compile(&(pf_surface){src, NULL, 0, NULL, 0});
            fns[i] = (ism_cut_fn){.tape = lin[i], .c = pl[i].d, .kind = ISM_CUT_LEVEL};
        } else {
            fns[i] = (ism_cut_fn){.n = {pl[i].n[0], pl[i].n[1], pl[i].n[2]}, .c = pl[i].d,
                                  .kind = ISM_CUT_SECTION};
        }
    }
    ism_cut cut;
    ism_arrangement arr;
    ism_error err;
    cr_assert(ism_curves_cut(f, fns, NPLANES, box, &m, &cut, &arr, &err), "%s", err.message);
    cr_log_info("ellipsoid x %d planes, box %d: %zu triangles; V E F %zu %zu %zu, closed form "
                "%zu %zu %zu", NPLANES, which, m.ntris, arr.nvertices, arr.nedges, arr.nfaces,
                x->v, x->e, x->f);
    cr_assert_eq(cut.unrefined, 0);
    cr_assert(arr.euler_ok);
    cr_assert_eq(arr.nvertices, x->v);
    cr_assert_eq(arr.nedges, x->e);
    cr_assert_eq(arr.nfaces, x->f);
    for (size_t i = 0; i < arr.nvertices; i++) { /* crossings at the closed-form points */
        if (arr.vertices[i].type != ISM_ARR_CROSSING)
            continue;
        const double *p = m.pos + 3 * (size_t)arr.vertices[i].v;
        double best = INFINITY;
        for (size_t k = 0; k < x->npts; k++) {
            double d[3] = {p[0] - x->pts[k][0], p[1] - x->pts[k][1], p[2] - x->pts[k][2]};
            best = fmin(best, sqrt(dot3(d, d)));
        }
        cr_assert_leq(best, tol, "crossing %zu off by %g", i, best);
    }
    double worst = 0, worst_sag = 0; /* no triangle left uncut: how far the lesser side
                                         reaches across, against the triangle's sagitta */
    size_t across = 0;
    for (size_t t = 0; t < m.ntris; t++)
        for (int i = 0; i < NPLANES; i++) {
            double lo = INFINITY, hi = -INFINITY, l2 = 0;
            for (int c = 0; c < 3; c++) {
                uint32_t v = m.tri[3 * t + c], w = m.tri[3 * t + (c + 1) % 3];
                double g = g_at(&m, &pl[i], v), d[3];
                lo = fmin(lo, g);
                hi = fmax(hi, g);
                for (int k = 0; k < 3; k++)
                    d[k] = m.pos[3 * (size_t)v + k] - m.pos[3 * (size_t)w + k];
                l2 = fmax(l2, dot3(d, d));
            }
            if (lo < -tol && hi > tol) {
                worst = fmax(worst, fmin(-lo, hi));
                worst_sag = fmax(worst_sag, fmin(-lo, hi) / (l2 * KAPPA_MAX / 8));
                across++;
            }
        }
    cr_log_info("box %d: %zu triangle-plane pairs with corners across, the lesser side %.2e "
                "(%.4f cell, %.3f of the triangle's sagitta)", which, across, worst,
                worst / cell, worst_sag);
    cr_assert_leq(worst_sag, 1.0);
    uint32_t *comp = malloc(m.ntris * sizeof *comp);
    size_t ncomp = flood_faces(&m, pl, tol, comp);
    cr_log_info("box %d: flood fill %zu faces, arrangement %zu", which, ncomp, arr.nfaces);
    cr_assert_eq(ncomp, arr.nfaces);
    same_partition(&arr, comp, ncomp, m.ntris);
    free(comp);
    ism_arrangement_free(&arr);
    ism_cut_free(&cut);
    for (int i = 0; i < NPLANES; i++)
        ism_tape_free(lin[i]);
    ism_mesh_free(&m);
    ism_tape_free(f);
    free(x);
}

Test(curves_cells, ellipsoid_planes) { ellipsoid_planes(0); }
Test(curves_cells, ellipsoid_planes_shift_1e3) { ellipsoid_planes(1); }
Test(curves_cells, ellipsoid_planes_shift_037) { ellipsoid_planes(2); }
