/* test_rm_merge_undo.c — rm_merge_unapply (core/remesh/rm_merge.c) undoes rm_merge_apply: on
 * a polygonised sphere, in the box on the lattice and both shifted ones, a chain of merges
 * into one vertex (as rm_horn.c's cone makes them: w's degree grows past the collapses'
 * limit) undone last first leaves every triangle's corners and dead mark, every vertex's set
 * of triangles (its slot's order may differ), gone and locked marks as they were; and the
 * mesh between the merges is closed (each live triangle in its corners' slots, χ = 2). */
#include <criterion/criterion.h>
#include <stdlib.h>
#include <string.h>

#include "core/remesh/rm_merge.h"
#include "tests/unit/core/poly_fixture.h"

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* χ of the live triangles counted from their corners, and whether every live triangle is in
 * each of its corners' slots. */
static long euler_checked(const rm_mesh *r, bool *slots_ok)
{
    const ism_mesh *m = r->m;
    uint8_t *used = calloc(m->nverts, 1);
    uint64_t *edges = malloc(3 * m->ntris * sizeof *edges);
    size_t ne = 0, nf = 0, nv = 0, distinct = 0;
    *slots_ok = true;
    for (size_t t = 0; t < m->ntris; t++) {
        if (r->dead[t])
            continue;
        nf++;
        for (int k = 0; k < 3; k++) {
            uint32_t a = m->tri[3 * t + k], b = m->tri[3 * t + (k + 1) % 3];
            used[a] = 1;
            edges[ne++] = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
            bool found = false;
            for (uint32_t i = 0; i < r->count[a]; i++)
                found |= r->vt[r->start[a] + i] == t;
            *slots_ok &= found;
        }
    }
    for (size_t v = 0; v < m->nverts; v++)
        nv += used[v];
    qsort(edges, ne, sizeof *edges, cmp_u64);
    for (size_t i = 0; i < ne; i++)
        distinct += i == 0 || edges[i] != edges[i - 1];
    free(used);
    free(edges);
    return (long)nv - (long)distinct + (long)nf;
}

/* What the merges may change: corners, dead marks, gone / locked marks, slots as sets. */
typedef struct state {
    uint32_t *tri, *slots, *count;
    uint8_t *dead, *gone, *locked;
    size_t nslots;
} state;

static void take(const rm_mesh *r, state *s)
{
    const ism_mesh *m = r->m;
    s->tri = malloc(3 * m->ntris * sizeof *s->tri);
    memcpy(s->tri, m->tri, 3 * m->ntris * sizeof *s->tri);
    s->dead = malloc(m->ntris), s->gone = malloc(m->nverts), s->locked = malloc(m->nverts);
    memcpy(s->dead, r->dead, m->ntris);
    memcpy(s->gone, r->gone, m->nverts);
    memcpy(s->locked, r->locked, m->nverts);
    s->count = malloc(m->nverts * sizeof *s->count);
    s->nslots = 0;
    for (size_t v = 0; v < m->nverts; v++)
        s->nslots += s->count[v] = r->count[v];
    s->slots = malloc((s->nslots ? s->nslots : 1) * sizeof *s->slots);
    size_t at = 0;
    for (size_t v = 0; v < m->nverts; v++) {
        memcpy(s->slots + at, r->vt + r->start[v], r->count[v] * sizeof *s->slots);
        qsort(s->slots + at, r->count[v], sizeof *s->slots, cmp_u32);
        at += r->count[v];
    }
}

static bool same(const state *a, const state *b, const ism_mesh *m)
{
    return a->nslots == b->nslots && !memcmp(a->tri, b->tri, 3 * m->ntris * sizeof *a->tri) &&
           !memcmp(a->dead, b->dead, m->ntris) && !memcmp(a->gone, b->gone, m->nverts) &&
           !memcmp(a->locked, b->locked, m->nverts) &&
           !memcmp(a->count, b->count, m->nverts * sizeof *a->count) &&
           !memcmp(a->slots, b->slots, a->nslots * sizeof *a->slots);
}

static void drop(state *s)
{
    free(s->tri), free(s->slots), free(s->count), free(s->dead), free(s->gone), free(s->locked);
}

/* Up to this many merges into the one vertex: its fan grows past ISM_RM_MERGE_MAX_DEGREE. */
#define CHAIN 16

Test(rm_merge_undo, a_chain_of_merges_undone_last_first_restores_the_mesh)
{
    const double base[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
    pf_surface sf = {.expr = "x^2 + y^2 + z^2 - 1"};
    ism_tape *tape = pf_compile(&sf);
    for (int which = -1; which < 2; which++) {
        double box[6];
        ism_mesh m;
        pf_props props;
        ism_mesh_init(&m);
        pf_run_placed(tape, base, 5, which, box, &m, &props);
        cr_assert_eq(props.euler, 2);
        rm_mesh r = {0};
        cr_assert(rm_mesh_build(&r, &m, 0));
        state before;
        take(&r, &before);
        uint32_t w = 0;
        rm_merge log[CHAIN];
        uint32_t fan[CHAIN][ISM_RM_MERGE_MAX_DEGREE], nfan[CHAIN];
        int n = 0;
        bool grew = false;
        while (n < CHAIN) { /* w's nearest mergeable neighbour, again and again */
            bool found = false;
            for (uint32_t i = 0; i < r.count[w] && !found; i++) {
                const uint32_t *t = m.tri + 3 * (size_t)r.vt[r.start[w] + i];
                for (int k = 0; k < 3 && !found; k++)
                    found = t[k] != w && rm_merge_find_into(&r, t[k], w, log + n) &&
                            rm_merge_link_ok(&r, log + n);
            }
            if (!found)
                break;
            cr_assert(rm_merge_apply(&r, log + n, fan[n], nfan + n));
            bool slots_ok;
            cr_expect_eq(euler_checked(&r, &slots_ok), 2, "box %d, merge %d", which, n);
            cr_expect(slots_ok, "box %d, merge %d", which, n);
            grew |= r.count[w] > ISM_RM_MERGE_MAX_DEGREE;
            n++;
        }
        cr_expect_eq(n, CHAIN, "box %d: %d merges", which, n);
        cr_expect(grew, "box %d: w's fan %u", which, r.count[w]);
        state merged;
        take(&r, &merged);
        cr_expect_not(same(&before, &merged, &m)); /* the merges did change it */
        drop(&merged);
        while (n--)
            rm_merge_unapply(&r, log + n, fan[n], nfan[n]);
        state after;
        take(&r, &after);
        cr_expect(same(&before, &after, &m), "box %d: not restored", which);
        drop(&before), drop(&after);
        rm_mesh_free(&r);
        ism_mesh_free(&m);
    }
    ism_tape_free(tape);
}
