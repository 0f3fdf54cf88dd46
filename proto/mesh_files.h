/* mesh_files.h — the PLY and OBJ the service sends: like core's writers (core/mesh/
 * write_mesh.h), plus what the wire carries. PLY: binary little endian, per vertex float x y z,
 * then the attributes the request asked for — float nx ny nz (unit everywhere), float
 * mean_curvature, float gauss_curvature (clamped as in Draco's), uchar class (features.h's
 * classes) — and faces as uchar 3 + int indices, then face properties uint cell (when
 * curves were requested: the arrangement face) and uchar double_sheet (when f has double
 * sheets). One row per mesh vertex and the mesh's faces, so the file is the mesh the stats
 * describe (vertices, edges, χ): a crease vertex's row carries the normalised sum of its
 * sides' normals (mesh_files.c says why), the corners at the singular locus with their
 * sheet's normal (wire_mesh.h's corner_locus) leave their vertex's row as it is; the
 * per-side and per-sheet normals travel in drc/glb (points split there) and the OBJ. OBJ: core's v / vn / f lines (a crease's other-side corners and the locus's
 * sheet corners with `vn` lines of their own; one `v` per mesh vertex), then the
 * features as `l` polylines over the same
 * 1-based vertices: a group `g nonmanifold_curves`, a group `g boundaries` (closed ones
 * repeat their first vertex), and per kind of requested curve a group `g section_curves`,
 * `level_curves`, ... with one `l` per arrangement edge. */
#ifndef ISM_MESH_FILES_H
#define ISM_MESH_FILES_H

#include <stdbool.h>

#include "core/mesh/write_mesh.h"
#include "proto/features.h"
#include "proto/wire_mesh.h"

/* PLY of m with w's attributes (those not NULL). False on a short write. */
bool ism_write_ply_wire(const ism_mesh *m, const ism_wire_mesh *w, ism_write_fn write,
                        void *ctx);

/* OBJ of m with w's corner normals (a crease's sides, the locus's sheets: extra `vn` lines
 * those corners use; w may be NULL) and f's curves and boundaries as `l` lines (f may be
 * NULL). */
bool ism_write_obj_features(const ism_mesh *m, const ism_wire_mesh *w, const ism_features *f,
                            ism_write_fn write, void *ctx);

#endif
