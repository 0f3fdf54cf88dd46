/* curve_cell.c — the cell a double curve asks for (see curve_cell.h). */
#include "core/singular/curve_cell.h"

#include <math.h>
#include "core/util/vec3.h"

double ism_curve_cell(const ism_sing_curve *cu, double finest, double tan_phi)
{
    if (cu->kind != ISM_CURVE_DOUBLE || cu->n < 2)
        return finest;
    double span2 = 0;
    for (size_t i = 1; i < cu->n; i++)
        span2 = fmax(span2, ism_sqdist3(cu->xyz, cu->xyz + 3 * i));
    /* fmin: a NAN angle (none measured) leaves the span's cell */
    double want = sqrt(span2) / ISM_CURVE_CELLS * fmin(1, tan_phi / ISM_CURVE_FULL_TAN);
    double cell = finest;
    /* the octree's cells halve: the first of finest / 2^k at most `want` (a bounded number of
     * halvings: the lattice holds ISM_CURVE_MAX_HALVINGS levels below the depth at most) */
    for (int k = 0; k < ISM_CURVE_MAX_HALVINGS && !(cell <= want); k++)
        cell /= 2;
    return cell;
}

double ism_curve_mesh_cell(const ism_sing_curve *cu, double finest)
{
    return cu->split_cell > 0 && cu->split_cell < finest ? cu->split_cell : finest;
}

double ism_point_curve_cell(const ism_locus *l, size_t i, double finest)
{
    double cell = finest;
    for (size_t k = 0; k < l->ncurves; k++) {
        const ism_sing_curve *cu = &l->curves[k];
        if (!cu->closed && (cu->end_point[0] == (int)i || cu->end_point[1] == (int)i))
            cell = fmin(cell, ism_curve_mesh_cell(cu, finest));
    }
    return cell;
}
