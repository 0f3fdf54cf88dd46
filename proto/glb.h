/* glb.h — glTF 2.0 binary (.glb) of one surface: the triangles as a Draco-compressed primitive
 * (KHR_draco_mesh_compression, attribute ids as in draco_encode.h) and, uncompressed beside
 * them, the features Draco cannot carry: non-manifold curves (LINES), non-manifold points
 * (POINTS) and boundary chains (LINES). Opens in three.js (GLTFLoader + DRACOLoader) and
 * Blender.
 *
 * Nodes, by name: "surface" (always, unless empty), "nonmanifold_curves",
 * "nonmanifold_points", "boundaries", and from the singular locus found from f
 * "singular_points" (POINTS; extras {"type": [...], "certified": [...], "xyz": [full
 * precision]}), "double_curves" and "whiskers" (LINES; extras {"kind", "curves"}) — each only
 * when there is something to draw; the requested curves as LINES nodes "section_curves",
 * "level_curves", "intersection_curves", "silhouette_curves", "crease_curves" (one polyline
 * per arrangement edge; extras {"kind", "curves", "curve": [each arc's curve, the features
 * JSON's order]}). The surface's attributes: POSITION, NORMAL, _MEAN_CURVATURE,
 * _GAUSS_CURVATURE, _CLASS (the ones sent), _CELL (the arrangement cell of the point's
 * triangles, float; when curves were requested) and _DOUBLE_SHEET (ubyte 0/1; when f has
 * double sheets) — vertices are split where cells or sheets change, so every triangle's
 * points agree; the points node carries "extras": {"class": [...], "kind": [...]} per point.
 * Without Draco (request output.draco false, ?draco=0) the surface is a plain primitive: the
 * same attributes as float/ubyte accessors and uint32 indices, no extension required.
 * An empty surface gives a valid glTF with one empty scene and no buffer. */
#ifndef ISM_GLB_H
#define ISM_GLB_H

#include <stddef.h>
#include <stdbool.h>
#include "proto/draco_encode.h"
#include "proto/features.h"
#include "proto/wire_mesh.h"

typedef struct ism_glb_input {
    const ism_mesh *mesh;             /* positions of feature vertices */
    const ism_wire_mesh *wire;        /* which attributes were sent, bounds */
    const ism_draco_output *draco;    /* NULL for an empty surface, or a plain glb (the
                                         surface then as uncompressed accessors) */
    const ism_features *features;     /* may be NULL */
    const char *key;                  /* cache key for asset.extras; may be NULL */
} ism_glb_input;

/* Builds the .glb into a malloc'd buffer. False when out of memory (or sizes overflow). */
bool ism_glb_build(const ism_glb_input *in, unsigned char **out, size_t *len);

#endif
