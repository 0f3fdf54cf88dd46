/* test_search_lines.c — the singular search (core/singular/search.h) on loci along the axes,
 * which lie on lattice lines of the symmetric box (there cells holding a segment of the locus
 * skip their tests, search.c "Segments of the locus on lattice lines") and inside cell
 * columns once the box moves by 1e-3 or by an irrational fraction of a cell.
 *
 * For xy, xyz and Whitney's x² − y²z every enclosure the tests take is exact enough to drop
 * each cell that does not meet the locus (∂f/∂x = y, yz, 2x are products of the box's own
 * intervals), so the candidates are, from the closed form, exactly the finest cells whose
 * closure meets the locus: in the symmetric box (N = 2^depth cells a side, the axes on cell
 * edges) 4 N round one axis and 12 N − 16 round three (4 N each, the 8 cells at the origin
 * counted three times instead of once); in a moved box (each axis inside one column of
 * cells) N and 3 N − 2. Each candidate is projected onto the locus within its cell grown by
 * half a cell, but for at most 24 within 2 cells of the pinch or triple point. A cell taken for one holding a segment that does not (a centre line or edge
 * given to the wrong child, a line certified without its gradient vanishing: xy's x and y
 * lines through the origin carry f = 0 but not ∇f = 0) is kept and counted. */
#include <criterion/criterion.h>
#include <math.h>

#include "core/singular/search.h"
#include "tests/unit/placements.h"

static ism_tape *compile(const char *src)
{
    ism_error err;
    ism_tape *t = ism_tape_compile(src, NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t, "%s: %s", src, err.message);
    return t;
}

/* The search of src in ±1 moved by shift (a multiple of a finest cell, or 1e-3) at depth d. */
static void search(const ism_tape *t, int depth, double shift, ism_locus *l)
{
    ism_locus_options o;
    ism_locus_options_default(&o);
    for (int k = 0; k < 3; k++) {
        o.box[k] = -1.0 + shift;
        o.box[k + 3] = 1.0 + shift;
    }
    o.max_depth = depth;
    o.threads = 1;
    ism_locus_init(l);
    ism_error err;
    cr_assert(ism_sing_search(t, &o, l, &err), "%s", err.message);
    cr_assert(!l->incomplete, "%s", l->incomplete_why);
}

/* How many of the coordinate axes named in axes (bit k: the axis along k) the point p lies
 * on within tol. */
static int on_axes(const double p[3], unsigned axes, double tol)
{
    int n = 0;
    for (int k = 0; k < 3; k++)
        if ((axes >> k) & 1u)
            n += fabs(p[(k + 1) % 3]) <= tol && fabs(p[(k + 2) % 3]) <= tol;
    return n;
}

static void check(const char *src, unsigned axes)
{
    ism_tape *t = compile(src);
    int naxes = (int)((axes & 1u) + ((axes >> 1) & 1u) + ((axes >> 2) & 1u));
    for (int depth = 4; depth <= 7; depth += 3)
        for (int placement = 0; placement < 3; placement++) {
            size_t n = (size_t)1 << depth;
            double cell = 2.0 / (double)n;
            double shift = placement == 0 ? 0.0 : placement == 1 ? 1e-3 : PF_IRR * cell;
            size_t want = placement == 0 ? (naxes == 1 ? 4 * n : 12 * n - 16)
                                         : (naxes == 1 ? n : 3 * n - 2);
            ism_locus l;
            size_t projected = 0;
            search(t, depth, shift, &l);
            cr_expect_eq(l.nboxes, want, "%s depth %d placement %d: %zu boxes, want %zu", src,
                         depth, placement, l.nboxes, want);
            for (size_t i = 0; i < l.nboxes; i++) {
                const ism_lbox *b = &l.boxes[i];
                bool meets = false;
                for (int k = 0; k < 3; k++) /* the closure meets an axis of the locus */
                    if ((axes >> k) & 1u)
                        meets = meets
                                || (b->lo[(k + 1) % 3] <= 0 && b->hi[(k + 1) % 3] >= 0
                                    && b->lo[(k + 2) % 3] <= 0 && b->hi[(k + 2) % 3] >= 0);
                cr_expect(meets, "%s depth %d placement %d: box %zu off the locus", src, depth,
                          placement, i);
                if (!(b->flags & ISM_LBOX_PROJECTED)) {
                    /* Newton may stall only beside the pinch or triple point, where ∇f
                     * vanishes to higher order */
                    for (int k = 0; k < 3; k++)
                        cr_expect(b->lo[k] >= -2.0 * cell - fabs(shift)
                                      && b->hi[k] <= 2.0 * cell + fabs(shift),
                                  "%s depth %d placement %d: box %zu not projected", src, depth,
                                  placement, i);
                    continue;
                }
                projected++;
                cr_expect_geq(on_axes(b->q, axes, 1e-9 * cell), 1,
                              "%s depth %d placement %d: box %zu projected to (%g, %g, %g)",
                              src, depth, placement, i, b->q[0], b->q[1], b->q[2]);
                for (int k = 0; k < 3; k++)
                    cr_expect(b->q[k] >= b->lo[k] - 0.5 * cell && b->q[k] <= b->hi[k] + 0.5 * cell,
                              "%s: box %zu projected outside its grown cell", src, i);
            }
            cr_expect_geq(projected + 24, l.nboxes, "%s depth %d placement %d: %zu of %zu projected",
                          src, depth, placement, projected, l.nboxes);
            ism_locus_free(&l);
        }
    ism_tape_free(t);
}

/* The double line x = y = 0 of two crossing planes. */
Test(singular_search_lines, crossing_planes) { check("x*y", 4u); }

/* The three double lines of the coordinate planes, meeting at the triple point. */
Test(singular_search_lines, coordinate_planes) { check("x*y*z", 7u); }

/* Whitney's umbrella: the z axis (double line above the pinch point, whisker below). */
Test(singular_search_lines, whitney_axis) { check("x^2 - y^2*z", 4u); }
