/* test_weld_normals.c — ism_weld's normals where ∇f vanished (weld.c fill_missing_normals):
 * the mean of the adjacent triangles' normals. A fan of 20,000 triangles (past two of weld.c's
 * blocks of 8,192) round an apex whose gradient is zero, over a rim that goes up and down so
 * that the triangles' normals differ, in three pieces that each hold their own copy of the
 * apex; and one rim point with a zero gradient too. Its normal against the sum of the
 * triangles' cross products worked out here, normalised; every other vertex's normal is its
 * own gradient's direction. The fan in its own place and moved by the placements' offsets
 * (tests/unit/placements.h). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/octree/weld.h"
#include "tests/unit/placements.h"

enum { FAN = 20000, PIECES = 3, FLAT_RIM = 12345 };

/* Rim point i of the fan round (0, 0, 0) (apex at shift), moved by shift. */
static void rim_point(size_t i, const double shift[3], double p[3])
{
    double t = 2 * M_PI * (double)i / FAN;
    p[0] = shift[0] + cos(t);
    p[1] = shift[1] + sin(t);
    p[2] = shift[2] + 0.3 * sin(7 * t) + 0.2 * cos(3 * t) - 0.4;
}

static void cross_of(const double a[3], const double b[3], const double c[3], double n[3])
{
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
}

static void near_unit(const float *got, const double want[3], const char *what)
{
    double len = sqrt(want[0] * want[0] + want[1] * want[1] + want[2] * want[2]);
    for (int k = 0; k < 3; k++)
        cr_assert(fabs(got[k] - want[k] / len) < 1e-6, "%s: component %d %.9g, want %.9g", what,
                  k, got[k], want[k] / len);
}

/* Piece k holds the apex (its own copy, first), then triangles [lo, hi) of the fan with their
 * two rim points each (copies too: the weld joins them). */
static void make_piece(size_t lo, size_t hi, const double shift[3], ism_cell_out *o)
{
    size_t nt = hi - lo;
    o->verts = calloc(1 + 2 * nt, sizeof *o->verts);
    o->tris = malloc(3 * nt * sizeof *o->tris);
    cr_assert(o->verts && o->tris);
    o->nverts = o->cap_verts = 1 + 2 * nt;
    o->ntris = o->cap_tris = nt;
    memcpy(o->verts[0].p, shift, sizeof o->verts[0].p); /* g 0 0 0 */
    for (size_t t = 0; t < nt; t++) {
        for (size_t s = 0; s < 2; s++) {
            size_t i = (lo + t + s) % FAN;
            ism_fpoint *v = &o->verts[1 + 2 * t + s];
            rim_point(i, shift, v->p);
            if (i != FLAT_RIM)
                for (int k = 0; k < 3; k++)
                    v->g[k] = v->p[k] - shift[k] + (k == 2 ? 1 : 0);
        }
        uint32_t *tri = o->tris + 3 * t;
        tri[0] = 0, tri[1] = (uint32_t)(1 + 2 * t), tri[2] = (uint32_t)(2 + 2 * t);
    }
}

Test(weld_normals, mean_of_the_triangles_where_the_gradient_vanishes)
{
    const double shifts[3][3] = {{0, 0, 0},
                                 {PF_OFF_X, PF_OFF_Y, PF_OFF_Z},
                                 {PF_IRR_X, PF_IRR_Y, PF_IRR_Z}};
    for (int w = 0; w < 3; w++) {
        const double *shift = shifts[w];
        ism_cell_out pieces[PIECES];
        memset(pieces, 0, sizeof pieces);
        size_t cut[PIECES + 1] = {0, 7000, 15500, FAN};
        for (int k = 0; k < PIECES; k++)
            make_piece(cut[k], cut[k + 1], shift, &pieces[k]);
        ism_mesh m;
        memset(&m, 0, sizeof m);
        ism_weld_stats st;
        cr_assert(ism_weld(pieces, PIECES, NULL, &m, &st, NULL));
        cr_assert_eq(m.ntris, FAN, "placement %d", w);
        cr_assert_eq(m.nverts, 1 + FAN, "placement %d: the copies joined", w);
        /* the apex is vertex 0 (first in piece 0), rim point i is vertex 1 + i (piece 0 meets
           them in order from rim point 0; the later pieces' are copies or continue it) */
        double apex[3] = {0, 0, 0}, flat[3] = {0, 0, 0};
        for (size_t t = 0; t < FAN; t++) {
            double a[3], b[3], n[3];
            rim_point(t, shift, a);
            rim_point((t + 1) % FAN, shift, b);
            cross_of(shift, a, b, n);
            for (int k = 0; k < 3; k++) {
                apex[k] += n[k];
                if (t == FLAT_RIM - 1 || t == FLAT_RIM)
                    flat[k] += n[k];
            }
        }
        cr_assert(!memcmp(m.pos, shift, 3 * sizeof *m.pos), "placement %d: apex first", w);
        near_unit(m.normal, apex, "apex");
        double p[3];
        rim_point(FLAT_RIM, shift, p);
        cr_assert(!memcmp(m.pos + 3 * (1 + FLAT_RIM), p, sizeof p), "placement %d", w);
        near_unit(m.normal + 3 * (1 + FLAT_RIM), flat, "rim point without a gradient");
        for (size_t i = 0; i < FAN; i += 997) { /* the others: their gradients */
            if (i == FLAT_RIM)
                continue;
            double g[3];
            rim_point(i, shift, p);
            for (int k = 0; k < 3; k++)
                g[k] = p[k] - shift[k] + (k == 2 ? 1 : 0);
            near_unit(m.normal + 3 * (1 + i), g, "rim point");
        }
        ism_mesh_free(&m);
        for (int k = 0; k < PIECES; k++) {
            free(pieces[k].verts);
            free(pieces[k].tris);
        }
    }
}
