/* test_root_table.c — the build's edge roots handed to the cells (core/octree/root_table.h):
 * logs gathered into one table keep each edge once with the first log's root, a hit gives the
 * exact parameter logged, a miss and an empty table answer false, a log stops at its limit;
 * and the premise that a hit is the cell's own search bit for bit: a form meshed with the
 * table and without it (scalar_eval: no memos, so no logs) gives the same triangles and the
 * same vertices, in the lattice box and the PF_OFF_* / PF_IRR_* boxes. */
#include <criterion/criterion.h>
#include <stdlib.h>
#include <string.h>
#include "poly_fixture.h"
#include "core/octree/grid.h"
#include "core/octree/root_table.h"

/* A lattice key as the build makes them (never 0). */
static uint64_t key(int32_t x, int32_t y, int32_t z)
{
    const int32_t p[3] = {x, y, z};
    return ism_lattice_key(p);
}

static ism_root_log log_of(size_t limit)
{
    ism_root_log l;
    memset(&l, 0, sizeof l);
    l.limit = limit;
    return l;
}

Test(root_table, an_edge_in_two_logs_is_kept_once_with_the_first_root)
{
    ism_root_log a = log_of(100), b = log_of(100);
    uint64_t e0 = key(0, 0, 0), e1 = key(1, 0, 0), f1 = key(0, 1, 0);
    ism_root_log_push(&a, e0, e1, 0.25);
    ism_root_log_push(&b, e0, e1, 0.75); /* disagrees: the first put wins */
    ism_root_log_push(&b, e0, f1, 0.5);
    size_t n = a.n + b.n;
    cr_assert_eq(n, 3);
    ism_root_table t;
    ism_root_table_init(&t, n);
    ism_root_table_take(&t, &a);
    ism_root_table_take(&t, &b);
    cr_expect_null(a.v, "a log is freed once in the table");
    cr_expect_null(b.v);
    size_t used = 0;
    for (size_t s = 0; s <= t.mask; s++)
        used += t.slots[s].a != 0;
    cr_expect_eq(used, 2, "%zu slots used for 2 edges", used);
    double r = -1;
    cr_expect(ism_root_table_find(&t, e0, e1, &r));
    cr_expect_eq(r, 0.25, "the first log's root: %.17g", r);
    cr_expect(ism_root_table_find(&t, e0, f1, &r));
    cr_expect_eq(r, 0.5, "%.17g", r);
    cr_expect_not(ism_root_table_find(&t, e1, e0, &r), "an edge is ordered: (b, a) misses");
    cr_expect_not(ism_root_table_find(&t, e0, key(0, 0, 1), &r));
    ism_root_table_free(&t);
}

Test(root_table, a_hit_returns_the_exact_parameter_among_many)
{
    ism_root_log l = log_of(5000);
    for (int i = 0; i < 4000; i++) /* enough for collisions and wrapped probe runs */
        ism_root_log_push(&l, key(i, 7, 3), key(i + 1, 7, 3), (i + 0.1) / 4001.0 + 1e-17 * i);
    cr_assert_eq(l.n, 4000);
    ism_root_table t;
    ism_root_table_init(&t, l.n);
    ism_root_table_take(&t, &l);
    for (int i = 0; i < 4000; i++) {
        double r = -1, want = (i + 0.1) / 4001.0 + 1e-17 * i;
        cr_assert(ism_root_table_find(&t, key(i, 7, 3), key(i + 1, 7, 3), &r), "edge %d", i);
        cr_assert_eq(r, want, "edge %d: %.17g != %.17g", i, r, want);
        cr_assert_not(ism_root_table_find(&t, key(i, 8, 3), key(i + 1, 8, 3), &r), "%d", i);
    }
    ism_root_table_free(&t);
}

Test(root_table, no_roots_no_slots_and_every_find_misses)
{
    ism_root_table t;
    ism_root_table_init(&t, 0);
    cr_expect_null(t.slots);
    cr_expect_eq(t.mask, 0);
    double r = 42;
    cr_expect_not(ism_root_table_find(&t, key(0, 0, 0), key(1, 0, 0), &r));
    cr_expect_not(ism_root_table_find(NULL, key(0, 0, 0), key(1, 0, 0), &r));
    cr_expect_eq(r, 42, "a miss leaves *out alone");
    ism_root_log l = log_of(10);
    ism_root_log_push(&l, key(0, 0, 0), key(1, 0, 0), 0.5);
    ism_root_table_take(&t, &l); /* a table without slots only frees the log */
    cr_expect_null(l.v);
    cr_expect_not(ism_root_table_find(&t, key(0, 0, 0), key(1, 0, 0), &r));
    ism_root_table_free(&t);
}

Test(root_table, a_log_stops_at_its_limit)
{
    ism_root_log l = log_of(3), none = log_of(0);
    for (int i = 0; i < 10; i++) {
        ism_root_log_push(&l, key(i, 0, 0), key(i + 1, 0, 0), 0.5);
        ism_root_log_push(&none, key(i, 0, 0), key(i + 1, 0, 0), 0.5);
    }
    cr_expect_eq(l.n, 3, "%zu roots kept past a limit of 3", l.n);
    cr_expect_eq(none.n, 0);
    cr_expect_null(none.v, "a log of limit 0 allocates nothing");
    ism_root_log_free(&l);
    ism_root_log_free(&none);
}

/* The mesh with the table and without it: scalar_eval runs the build without its memos, so
 * nothing is logged and every cell searches its own roots. Same triangle count and the same
 * vertex positions, bit for bit (the meshes' vertex arrays compared sorted), in all three
 * boxes, under an error bound (the build's regula falsi roots, cell_error.c) and without. */
static int cmp_vertex(const void *a, const void *b)
{
    return memcmp(a, b, 3 * sizeof(double));
}

static double *sorted_vertices(const ism_mesh *m)
{
    double *v = malloc(3 * m->nverts * sizeof *v);
    cr_assert(v);
    memcpy(v, m->pos, 3 * m->nverts * sizeof *v);
    qsort(v, m->nverts, 3 * sizeof *v, cmp_vertex);
    return v;
}

Test(root_table, the_mesh_is_the_same_without_the_table, .timeout = 120)
{
    pf_surface s = {"x^4 + y^4 + z^4 - 1 + 0.3 * sin(3 * x) * y", NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    const double base[6] = {-1.4, -1.4, -1.4, 1.4, 1.4, 1.4};
    for (int w = pf_first_box() - 1; w < 2; w++)
        for (int bound = 0; bound < 2; bound++) {
            double box[6];
            pf_sweep_box(base, 7, w, box);
            ism_mesh m[2];
            ism_poly_stats st;
            for (int scalar = 0; scalar < 2; scalar++) {
                ism_poly_options o;
                pf_options(&o, box, 3, 7);
                o.threads = 1;
                o.max_error = bound ? pf_default_error(box) * 3 : 0;
                o.dual = false; /* the primal cells: those that ask the table */
                o.scalar_eval = scalar;
                pf_run_options(t, &o, &m[scalar], &st);
            }
            cr_expect_gt(m[0].ntris, 1000, "box %d bound %d: %zu triangles", w, bound,
                         m[0].ntris);
            cr_expect_eq(m[0].ntris, m[1].ntris, "box %d bound %d: %zu vs %zu triangles", w,
                         bound, m[0].ntris, m[1].ntris);
            if (m[0].nverts == m[1].nverts) {
                double *a = sorted_vertices(&m[0]), *b = sorted_vertices(&m[1]);
                cr_expect(memcmp(a, b, 3 * m[0].nverts * sizeof *a) == 0,
                          "box %d bound %d: vertex sets differ", w, bound);
                free(a);
                free(b);
            } else {
                cr_expect_fail("box %d bound %d: %zu vs %zu vertices", w, bound, m[0].nverts,
                               m[1].nverts);
            }
            ism_mesh_free(&m[0]);
            ism_mesh_free(&m[1]);
        }
    ism_tape_free(t);
}
