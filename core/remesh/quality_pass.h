/* quality_pass.h — the quality pass and the simplification applied to a surface's finished
 * mesh (after the conformance to the singular locus and the curve cuts): what the locus and
 * the cut say is protected is handed to ism_remesh_quality or ism_remesh_simplify. The
 * daemon's pipeline and the command line both call them. */
#ifndef ISM_QUALITY_PASS_H
#define ISM_QUALITY_PASS_H

#include "core/curves/cut.h"
#include "core/remesh/remesh.h"
#include "core/remesh/simplify.h"
#include "core/singular/locus.h"

/* The request's choice: the polygoniser's triangles as they come, or the pass run on them. */
enum ism_quality { ISM_QUALITY_RAW = 0, ISM_QUALITY_GOOD = 1, ISM_QUALITY_COUNT };

/* "raw" / "good", and back (-1 for an unknown name). */
const char *ism_quality_name(enum ism_quality q);
int ism_quality_lookup(const char *name);

/* Runs the pass on mesh: the locus's singular points' vertices stay, each double sheet's
 * triangles are a patch of their own, and cut's edges (may be NULL) are never flipped or
 * collapsed. What collapses renumber is renumbered with the mesh: cut's edges and triangle
 * parents, and the double sheets' triangle ranges when they index this mesh (no cut parents).
 * max_error as in ism_remesh_options. False with err set when out of memory (the mesh is then
 * still valid, and still agrees with the locus and the cut). */
bool ism_quality_pass(const ism_tape *f, ism_locus *locus, ism_cut *cut,
                      double max_error, const volatile int *cancel, ism_mesh *mesh,
                      ism_remesh_stats *st, ism_error *err);

/* Runs the simplification (simplify.h) within max_error (> 0) on mesh with the same
 * protection and renumbering as ism_quality_pass. False with err set when out of memory
 * (the mesh is then still valid and within the bound). */
bool ism_simplify_pass(const ism_tape *f, ism_locus *locus, ism_cut *cut,
                       double max_error, const volatile int *cancel, ism_mesh *mesh,
                       ism_simplify_stats *st, ism_error *err);

#endif
