/* draco_encode.h — the C face of the project's only C++ file (draco_encode.cc): one indexed
 * triangle mesh with its per-vertex attributes in, one Draco bitstream out (Debian's
 * libdraco 1.5.5, edgebreaker). Every C++ exception is caught inside; failures come back as
 * false with a message.
 *
 * Attribute ids — the wire contract with the viewer. Draco reorders and splits vertices, so a
 * decoder must find each attribute by its unique id (or by the metadata entry "name"), never
 * by position in the file. The ids are FIXED whatever subset is sent (an attribute that is
 * not sent is simply absent; the others keep their ids):
 *
 *   unique id  metadata name      Draco type  data     components  meaning
 *   0          "position"         POSITION    float32  3           x y z
 *   1          "normal"           NORMAL      float32  3           unit ∇f / |∇f| (on a
 *                                                                  crease: each side's branch)
 *   2          "mean_curvature"   GENERIC     float32  1           H (analysis.h's sign)
 *   3          "gauss_curvature"  GENERIC     float32  1           K
 *   4          "class"            GENERIC     uint8    1           enum ism_vertex_class
 *   5          "cell"             GENERIC     uint32   1           arrangement face (cell) id
 *   6          "double_sheet"     GENERIC     uint8    1           1 on a double sheet, else 0
 *
 * "cell" and "double_sheet" label triangles: the caller splits vertices where they change
 * (proto/corner_split.h), so all three points of a decoded triangle carry its label. They are
 * sent whenever the surface has them (cells: curves were requested; sheets: f has double
 * sheets).
 *
 * three.js: DRACOLoader finds position and normal by type; for the others use the decoder's
 * GetAttributeByUniqueId(mesh, id) (glTF: the KHR_draco_mesh_compression "attributes" map
 * carries the same ids). */
#ifndef ISM_DRACO_ENCODE_H
#define ISM_DRACO_ENCODE_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>

#ifdef __cplusplus
extern "C" {
#endif

enum ism_draco_id {
    ISM_DRACO_ID_POSITION = 0,
    ISM_DRACO_ID_NORMAL = 1,
    ISM_DRACO_ID_MEAN_CURVATURE = 2,
    ISM_DRACO_ID_GAUSS_CURVATURE = 3,
    ISM_DRACO_ID_CLASS = 4,
    ISM_DRACO_ID_CELL = 5,
    ISM_DRACO_ID_DOUBLE_SHEET = 6,
};

/* Draco's tools. speed 0 (smallest) .. 10 (fastest) picks them all; the other fields override
 * one choice (0 = what the speed picks). */
enum ism_draco_connectivity {
    ISM_DRACO_CONN_BY_SPEED = 0,
    ISM_DRACO_CONN_STANDARD,        /* edgebreaker, standard symbols */
    ISM_DRACO_CONN_VALENCE,         /* edgebreaker, valence-coded symbols (speeds 0-4) */
};
enum ism_draco_prediction {
    ISM_DRACO_PRED_BY_SPEED = 0,
    ISM_DRACO_PRED_DIFFERENCE,
    ISM_DRACO_PRED_PARALLELOGRAM,          /* speeds 2-7 */
    ISM_DRACO_PRED_CONSTRAINED_MULTI,      /* speeds 0-1 */
};
typedef struct ism_draco_tools {
    int speed;
    enum ism_draco_connectivity connectivity;
    enum ism_draco_prediction position_prediction;
} ism_draco_tools;

/* The service's tools (the measurement that chose them: draco_encode.cc). They enter the
 * cache key: changing them changes the bytes. */
extern const ism_draco_tools ism_draco_default_tools;

typedef struct ism_draco_input {
    size_t nverts, ntris;
    const float *pos;               /* 3 per vertex */
    const uint32_t *tri;            /* 3 per triangle, indices < nverts */
    const float *normal;            /* 3 per vertex, unit length; NULL = not sent */
    const float *mean_curvature;    /* 1 per vertex; NULL = not sent */
    const float *gauss_curvature;   /* 1 per vertex; NULL = not sent */
    const uint8_t *vertex_class;    /* 1 per vertex; NULL = not sent */
    int position_bits;              /* quantisation over the mesh's bounding cube (1..30) */
    int normal_bits;                /* octahedral quantisation of normals */
    int curvature_bits;             /* 0 = float32 as given, else quantised */
    const ism_draco_tools *tools;   /* NULL = ism_draco_default_tools */
    /* Points split from the vertices (corner_split.h): when point_vertex is set, tri indexes
     * npoints points and point p shows vertex point_vertex[p]; else points are vertices. */
    size_t npoints;
    const uint32_t *point_vertex;
    const uint32_t *point_cell;     /* 1 per point; NULL = not sent */
    const uint8_t *point_sheet;     /* 1 per point; NULL = not sent */
    const float *point_normal;      /* 3 per point (a crease's sides: corner_split.h); when
                                       set, sent as the normal instead of normal */
} ism_draco_input;

typedef struct ism_draco_output {
    unsigned char *data;            /* malloc'd bitstream (free()) */
    size_t len;
    size_t points, faces;           /* what a decoder will get (after Draco's splits and
                                       dropped degenerate faces) */
    char error[200];
} ism_draco_output;

/* Encodes. The mesh must have at least one triangle whose three indices differ (Draco
 * refuses a mesh of degenerate triangles: answer empty meshes without calling this). */
bool ism_draco_encode(const ism_draco_input *in, ism_draco_output *out);

#ifdef __cplusplus
}
#endif

#endif
