/* curves.h — the curves stage of a surface: after the mesh is made (and conformed to the
 * singular locus), it is cut along each requested curve f = 0, g = 0 and its arrangement
 * built. */
#ifndef ISM_CURVES_H
#define ISM_CURVES_H

#include "core/curves/arrangement.h"
#include "core/curves/cut.h"

/* Curve vertices are put within this × the box diagonal of both surfaces (the issue's
 * precision; Newton usually ends far below it). */
#define ISM_CURVE_TOL_REL 1e-10

/* Cuts mesh along fns[0..n) (cut overwritten; free with ism_cut_free). False with err set
 * when out of memory. */
bool ism_curves_cut_mesh(const ism_tape *f, const ism_cut_fn *fns, size_t n,
                         const double box[6], ism_mesh *mesh, ism_cut *cut, ism_error *err);

/* Cuts mesh along fns[0..n) and builds the arrangement without a singular locus (cut and
 * arr are overwritten; free them with ism_cut_free / ism_arrangement_free). False with err set when out of memory. */
bool ism_curves_cut(const ism_tape *f, const ism_cut_fn *fns, size_t n, const double box[6],
                    ism_mesh *mesh, ism_cut *cut, ism_arrangement *arr, ism_error *err);

#endif
