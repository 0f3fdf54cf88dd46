/* test_analysis_random.c — the analysis against a deliberately naive reference on random
 * triangle soups (few vertices, so edges with many triangles, shared apexes, duplicates and
 * collapsed triangles abound). The reference answers each question the slow, obvious way
 * (quadratic scans, per-vertex searches), sharing no code with core/analysis. */
#include <criterion/criterion.h>
#include <stdlib.h>
#include <string.h>

#include "core/analysis/analysis.h"

#define MAXV 24
#define MAXT 40
#define MAXE (3 * MAXT)

typedef struct soup {
    int nv, nt;
    int tri[MAXT][3];
} soup;

typedef struct naive {
    int ne, ends[MAXE][2], ntri[MAXE], tris[MAXE][MAXT];
    int cls[MAXV];
    long euler;
    int components, vertex_components, duplicates;
    bool orientable;
} naive;

static unsigned next_random(unsigned *s)
{
    *s = *s * 1103515245u + 12345u;
    return (*s >> 16) & 0x7fff;
}

static bool collapsed(const soup *s, int t)
{
    const int *c = s->tri[t];
    return c[0] == c[1] || c[1] == c[2] || c[0] == c[2];
}

static int find(int *p, int x)
{
    while (p[x] != x)
        x = p[x];
    return x;
}

static int edge_of(naive *n, int a, int b)
{
    int lo = a < b ? a : b, hi = a < b ? b : a;
    for (int e = 0; e < n->ne; e++)
        if (n->ends[e][0] == lo && n->ends[e][1] == hi)
            return e;
    n->ends[n->ne][0] = lo;
    n->ends[n->ne][1] = hi;
    n->ntri[n->ne] = 0;
    return n->ne++;
}

static bool has_vertex(const soup *s, int t, int v)
{
    return s->tri[t][0] == v || s->tri[t][1] == v || s->tri[t][2] == v;
}

/* +1 when triangle t runs from a to b, -1 when from b to a */
static int direction(const soup *s, int t, int a, int b)
{
    for (int k = 0; k < 3; k++)
        if (s->tri[t][k] == a && s->tri[t][(k + 1) % 3] == b)
            return 1;
    return -1;
}

static void reference_edges(const soup *s, naive *n)
{
    for (int t = 0; t < s->nt; t++)
        if (!collapsed(s, t))
            for (int k = 0; k < 3; k++) {
                int e = edge_of(n, s->tri[t][k], s->tri[t][(k + 1) % 3]);
                n->tris[e][n->ntri[e]++] = t;
            }
}

/* Class by the definition: cones = groups of the vertex's triangles joined across its
 * manifold edges. */
static void reference_classes(const soup *s, naive *n)
{
    for (int v = 0; v < s->nv; v++) {
        int p[MAXT], used = 0;
        bool nm = false, boundary = false;
        for (int t = 0; t < s->nt; t++) {
            p[t] = t;
            used += !collapsed(s, t) && has_vertex(s, t, v);
        }
        for (int e = 0; e < n->ne; e++) {
            if (n->ends[e][0] != v && n->ends[e][1] != v)
                continue;
            nm = nm || n->ntri[e] > 2;
            boundary = boundary || n->ntri[e] == 1;
            if (n->ntri[e] == 2)
                p[find(p, n->tris[e][0])] = find(p, n->tris[e][1]);
        }
        int cones = 0;
        for (int t = 0; t < s->nt; t++)
            cones += !collapsed(s, t) && has_vertex(s, t, v) && find(p, t) == t;
        n->cls[v] = !used ? 4 : nm ? 2 : cones > 1 ? 3 : boundary ? 1 : 0;
    }
}

static void reference_topology(const soup *s, naive *n)
{
    int p[MAXT], pv[MAXV], used = 0, valid = 0;
    for (int t = 0; t < s->nt; t++)
        p[t] = t;
    for (int v = 0; v < s->nv; v++)
        pv[v] = v;
    for (int e = 0; e < n->ne; e++)
        for (int i = 1; i < n->ntri[e]; i++)
            p[find(p, n->tris[e][i])] = find(p, n->tris[e][0]);
    n->components = n->vertex_components = 0;
    for (int t = 0; t < s->nt; t++) {
        if (collapsed(s, t))
            continue;
        valid++;
        n->components += find(p, t) == t;
        pv[find(pv, s->tri[t][0])] = find(pv, s->tri[t][1]);
        pv[find(pv, s->tri[t][1])] = find(pv, s->tri[t][2]);
    }
    for (int v = 0; v < s->nv; v++)
        if (n->cls[v] != 4) {
            used++;
            n->vertex_components += find(pv, v) == v;
        }
    n->euler = used - n->ne + valid;
}

/* Two-colouring of the triangles across manifold edges, flooded from one seed triangle at a
 * time: orientable when no edge clashes. */
static void reference_orientation(const soup *s, naive *n)
{
    int colour[MAXT];
    for (int t = 0; t < s->nt; t++)
        colour[t] = -1;
    n->orientable = true;
    for (int seed = 0; seed < s->nt; seed++) {
        if (collapsed(s, seed) || colour[seed] >= 0)
            continue;
        colour[seed] = 0;
        for (bool changed = true; changed;) {
            changed = false;
            for (int e = 0; e < n->ne; e++) {
                if (n->ntri[e] != 2)
                    continue;
                int a = n->tris[e][0], b = n->tris[e][1];
                int flip = direction(s, a, n->ends[e][0], n->ends[e][1]) ==
                           direction(s, b, n->ends[e][0], n->ends[e][1]);
                if (colour[a] >= 0 && colour[b] < 0) {
                    colour[b] = colour[a] ^ flip;
                    changed = true;
                } else if (colour[b] >= 0 && colour[a] < 0) {
                    colour[a] = colour[b] ^ flip;
                    changed = true;
                } else if (colour[a] >= 0 && colour[a] != (colour[b] ^ flip)) {
                    n->orientable = false;
                }
            }
        }
    }
}

static int cmp_int(const void *x, const void *y) { return *(const int *)x - *(const int *)y; }

static void reference_duplicates(const soup *s, naive *n)
{
    n->duplicates = 0;
    for (int t = 0; t < s->nt; t++) {
        if (collapsed(s, t))
            continue;
        int a[3] = {s->tri[t][0], s->tri[t][1], s->tri[t][2]};
        qsort(a, 3, sizeof *a, cmp_int);
        for (int u = 0; u < t; u++) {
            int b[3] = {s->tri[u][0], s->tri[u][1], s->tri[u][2]};
            qsort(b, 3, sizeof *b, cmp_int);
            if (!collapsed(s, u) && memcmp(a, b, sizeof a) == 0) {
                n->duplicates++;
                break;
            }
        }
    }
}

/* A closed band of q quads on shuffled vertex numbers, with a half twist or not. */
static int random_band(soup *s, unsigned *seed)
{
    int q = 3 + (int)(next_random(seed) % 6), perm[MAXV];
    bool twist = next_random(seed) % 2;
    s->nv = 2 * q + (int)(next_random(seed) % 4);
    for (int v = 0; v < s->nv; v++)
        perm[v] = v;
    for (int v = s->nv - 1; v > 0; v--) {
        int j = (int)(next_random(seed) % (v + 1)), x = perm[v];
        perm[v] = perm[j];
        perm[j] = x;
    }
    for (int i = 0; i < q; i++) {
        int t0 = i, b0 = q + i, t1 = i + 1, b1 = q + i + 1;
        if (i == q - 1) {
            t1 = twist ? q : 0;
            b1 = twist ? 0 : q;
        }
        int quad[2][3] = {{t0, b0, b1}, {t0, b1, t1}};
        for (int k = 0; k < 2; k++)
            for (int j = 0; j < 3; j++)
                s->tri[2 * i + k][j] = perm[quad[k][j]];
    }
    return 2 * q;
}

static void random_soup(soup *s, unsigned *seed)
{
    int first = 0;
    s->nv = 3 + (int)(next_random(seed) % (MAXV - 3));
    if (next_random(seed) % 4 == 0)
        first = random_band(s, seed);
    if (first) /* a few extra triangles, so that the band often survives */
        s->nt = first + (int)(next_random(seed) % 4);
    else
        s->nt = 1 + (int)(next_random(seed) % MAXT);
    for (int t = first; t < s->nt; t++) {
        unsigned kind = next_random(seed) % 10;
        int *c = s->tri[t];
        if (kind == 0 && t > 0) { /* an earlier triangle again, flipped */
            const int *o = s->tri[next_random(seed) % t];
            c[0] = o[2], c[1] = o[1], c[2] = o[0];
        } else {
            c[0] = (int)(next_random(seed) % s->nv);
            do
                c[1] = (int)(next_random(seed) % s->nv);
            while (kind != 1 && c[1] == c[0]); /* kind 1 may collapse */
            do
                c[2] = (int)(next_random(seed) % s->nv);
            while (c[2] == c[0] || c[2] == c[1]);
        }
    }
}

/* Every non-manifold edge in exactly one curve; chains pass only through vertices with two
 * non-manifold edges. */
static void check_curves(const naive *n, const ism_analysis *a)
{
    int seen[MAXE] = {0}, degree[MAXV] = {0};
    for (int e = 0; e < n->ne; e++)
        if (n->ntri[e] > 2) {
            degree[n->ends[e][0]]++;
            degree[n->ends[e][1]]++;
        }
    for (size_t c = 0; c < a->ncurves; c++) {
        uint32_t s0 = a->curve_start[c], s1 = a->curve_start[c + 1];
        cr_assert_geq(s1 - s0, 2);
        for (uint32_t i = s0; i + 1 < s1; i++) {
            int u = (int)a->curve_verts[i], w = (int)a->curve_verts[i + 1], e = -1;
            for (int k = 0; k < n->ne; k++)
                if (n->ends[k][0] == (u < w ? u : w) && n->ends[k][1] == (u < w ? w : u))
                    e = k;
            cr_assert(e >= 0 && n->ntri[e] > 2, "curve step %d-%d is no non-manifold edge",
                      u, w);
            seen[e]++;
            if (i > s0)
                cr_assert_eq(degree[u], 2, "curve passes through a vertex of degree %d",
                             degree[u]);
        }
    }
    for (int e = 0; e < n->ne; e++)
        if (n->ntri[e] > 2)
            cr_assert_eq(seen[e], 1, "non-manifold edge in %d curves", seen[e]);
}

Test(analysis_random, soups_agree_with_the_naive_reference)
{
    unsigned seed = 12345;
    int rounds = getenv("ISOMESH_TEST_QUICK") ? 500 : 3000;
    int with_nm = 0, with_cones = 0, with_duplicates = 0, non_orientable = 0, closed_curves = 0;
    for (int round = 0; round < rounds; round++) {
        soup s;
        random_soup(&s, &seed);
        naive n;
        memset(&n, 0, sizeof n);
        reference_edges(&s, &n);
        reference_classes(&s, &n);
        reference_topology(&s, &n);
        reference_orientation(&s, &n);
        reference_duplicates(&s, &n);
        ism_mesh m;
        ism_mesh_init(&m);
        for (int v = 0; v < s.nv; v++) {
            double p[3] = {v, v * v % 7, v % 3};
            cr_assert_neq(ism_mesh_add_vertex(&m, p, NULL), UINT32_MAX);
        }
        for (int t = 0; t < s.nt; t++)
            cr_assert(ism_mesh_add_triangle(&m, s.tri[t][0], s.tri[t][1], s.tri[t][2]));
        ism_analysis a;
        ism_error err;
        cr_assert(ism_analyse(&m, NULL, NULL, &a, &err), "%s", err.message);
        size_t nb = 0, nm = 0;
        for (int e = 0; e < n.ne; e++) {
            nb += n.ntri[e] == 1;
            nm += n.ntri[e] > 2;
        }
        cr_assert_eq(a.edges, (size_t)n.ne, "round %d", round);
        cr_assert_eq(a.boundary_edges, nb, "round %d", round);
        cr_assert_eq(a.nonmanifold_edges, nm, "round %d", round);
        for (int v = 0; v < s.nv; v++)
            cr_assert_eq(a.vertex_class[v], n.cls[v], "round %d vertex %d", round, v);
        cr_assert_eq(a.euler, n.euler, "round %d", round);
        cr_assert_eq(a.components, (size_t)n.components, "round %d", round);
        cr_assert_eq(a.vertex_components, (size_t)n.vertex_components, "round %d", round);
        cr_assert_eq(a.orientable, n.orientable, "round %d", round);
        cr_assert_eq(a.duplicate_triangles, (size_t)n.duplicates, "round %d", round);
        check_curves(&n, &a);
        with_nm += nm > 0;
        with_cones += a.class_count[ISM_VERTEX_NONMANIFOLD_POINT] > 0;
        with_duplicates += n.duplicates > 0;
        non_orientable += !n.orientable;
        for (size_t c = 0; c < a.ncurves; c++)
            closed_curves +=
                a.curve_verts[a.curve_start[c]] == a.curve_verts[a.curve_start[c + 1] - 1];
        ism_analysis_free(&a);
        ism_mesh_free(&m);
    }
    /* the soups did exercise what they are for */
    cr_expect_gt(with_nm, rounds / 10, "%d rounds with non-manifold edges", with_nm);
    cr_expect_gt(with_cones, rounds / 10, "%d rounds with several cones", with_cones);
    cr_expect_gt(with_duplicates, rounds / 10, "%d rounds with duplicates", with_duplicates);
    cr_expect_gt(non_orientable, rounds / 50, "%d non-orientable rounds", non_orientable);
    cr_expect_gt(closed_curves, 0, "no closed curve");
    cr_log_info("%d rounds: %d non-manifold, %d cones, %d duplicates, %d non-orientable, "
                "%d closed curves", rounds, with_nm, with_cones, with_duplicates,
                non_orientable, closed_curves);
}
