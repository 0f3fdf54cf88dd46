/* surface.h — one surface from f to a mesh that conforms to its singular locus, the order of
 * the phases in one place (the daemon's pipeline and the command line both call it):
 *
 *     f ──▶ singular locus (interval search, certified points, traced curves)
 *       ──▶ polygoniser (Balsys–Suffern octree)
 *       ──▶ double sheets (zero sets without a sign change) added to the mesh
 *       ──▶ the mesh made to conform to the locus (nodes one vertex, double curves edges) */
#ifndef ISM_SURFACE_H
#define ISM_SURFACE_H

#include "core/mesh/mesh.h"
#include "core/octree/polygonise.h"
#include "core/singular/conform.h"
#include "core/singular/locus.h"

typedef struct ism_surface_times {
    double singular_ms;  /* finding the locus, meshing double sheets, conforming */
    double polygonise_ms;
    double singular_cpu_ms, polygonise_cpu_ms; /* the same phases in process CPU time (all
                                                  threads; ism_cpu_ms) */
} ism_surface_times;

/* The depth that sizes the singular stage: depth.max, or under max_error the first depth (not
 * below 7) whose cell is at most 5 E (surface.c). */
int ism_singular_depth(const ism_poly_options *po);

/* The locus options that go with polygoniser options: the same box, depth
 * (ism_singular_depth), threads, cancellation and deadline. */
void ism_locus_options_from_poly(const ism_poly_options *po, ism_locus_options *lo);

/* Meshes f = 0 in po->box: mesh (initialised by the caller) gets the conforming mesh, locus
 * (initialised by the caller) what was found from f, cs what the conformance pass did.
 * Returns the polygoniser's status (BAD_OPTIONS, NO_MEMORY also for the locus stages); a
 * locus stage cut short by its budget or po->deadline_ms marks locus->incomplete (the reason
 * in incomplete_why) and the mesh is still returned, conformed as far as the pass got
 * (a locus cut short before the polygoniser: hidden pieces chased as without a locus). */
enum ism_poly_status ism_mesh_surface(const ism_tape *f, const ism_poly_options *po,
                                      ism_mesh *mesh, ism_locus *locus, ism_poly_stats *ps,
                                      ism_conform_stats *cs, ism_surface_times *times,
                                      ism_error *err);

#endif
