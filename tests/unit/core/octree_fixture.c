/* octree_fixture.c — one adapted octree for structure tests (octree_fixture.h). */
#include "octree_fixture.h"

#include <criterion/criterion.h>
#include <string.h>
#include "core/octree/octree_build.h"
#include "poly_fixture.h"

void of_build_swept(const ism_tape *t, double half, int max_depth, double max_error,
                    int placement, ism_octree *tree)
{
    const double base[6] = {-half, -half, -half, half, half, half};
    double box[6];
    pf_sweep_box(base, max_depth, placement, box);
    memset(tree, 0, sizeof *tree);
    ism_grid_init(&tree->grid, box, max_depth);
    ism_octree_build_params p = {
        .tape = t,
        .min_depth = 3,
        .max_depth = max_depth,
        .flatness = {.gradient_test = 0.9, .normal_cos = 0.9, .plane_frac = 0.05,
                     .abs_tol = 0.25 * ism_grid_cell_size(&tree->grid, max_depth),
                     .double_root_eps = 1e-9, .double_root_iters = 25, .max_error = max_error},
        .threads = 1,
        .max_nodes = (size_t)1 << 26,
    };
    ism_octree_build_stats st;
    cr_assert_eq(ism_octree_build(tree, &p, &st), ISM_BUILD_OK);
}
