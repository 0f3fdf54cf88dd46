/* computed.h — one surface computed once: the indexed mesh, every per-vertex attribute an
 * encoder can send, the features and the stats figures that do not depend on the encoding.
 * Every format, Draco quantisation and attribute set of that surface is encoded from it
 * (server/common/pipeline.h), so asking for a second format never polygonises again.
 *
 * Its binary form is the cache entry "<surface key>.mesh" (the surface key names the surface
 * and its accuracy, not the encoding: proto/request.h). Entry format, version 7 (5: the
 * corners' locus marks added, so the PLY keeps one row per vertex at the singular locus; 6:
 * the same layout, the locus corners' normals joined per half-sheet (proto/sheet_groups.h),
 * so a version 5 entry would still send one point per corner; 7: each singular curve's
 * certificate), all numbers little endian,
 * built from the length-prefixed fields of proto/frame.h:
 *
 *   bytes "ISMS", u32 version (ISM_COMPUTED_VERSION), string surface key (64 hex),
 *   u32 empty, u64 nverts, u64 ntris,
 *   bytes pos (f64 x 3 x nverts), bytes normal (f32 x 3 x nverts, the mesh's own),
 *   bytes tri (u32 x 3 x ntris),
 *   bytes wire_pos (f32 x 3), bytes wire_normal (f32 x 3), bytes mean, bytes gauss (f32 each;
 *   empty when not computed), bytes class (u8; empty when none), u64 live_triangles,
 *   bytes bounds (f64 x 6),
 *   polylines curves, polylines boundaries (each: bytes start u32 x (n + 1), bytes verts u32),
 *   bytes points (u32), bytes point_kind (u8), bytes point_class (u8),
 *   polylines arcs (of the requested curves), bytes arc_kind (u8), bytes arc_curve (u32),
 *   u64 singular points, each: bytes xyz (f64 x 3), u32 type, u32 certified,
 *   u64 singular curves, each: u32 kind, u32 closed, per end (2): u32 end type, u32 end point
 *   (index into the singular points; 0xffffffff: none), u64 split cell (the bits of an f64:
 *   the cell the octree split its nodes to along it, 0: the depth's), u32 certified,
 *   u64 uncertified points, u64 first uncertified (0xffffffffffffffff: none), u64 x 3 (f64
 *   bits: |f| and |∇f| there, the largest certificate half-width), bytes xyz (f64 x 3 x n),
 *   bytes corner_at (u32 x n, ascending corner indices 3 t + k < 3 ntris),
 *   bytes corner_normal (f32 x 3 x n) (both empty when no corner has a normal of its own),
 *   bytes corner_locus (u8 x n: 1 for a sheet normal at the singular locus, 0 for a crease
 *   side; empty when no corner is on the locus),
 *   bytes timings (f64 x ISM_TIME_COUNT), bytes features JSON, bytes stats JSON.
 *
 * A reader refuses any other version, magic, length or an index out of range (the entry is
 * then recomputed); a new layout takes a new version number. */
#ifndef ISM_COMPUTED_H
#define ISM_COMPUTED_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>

#include "core/mesh/mesh.h"
#include "core/singular/locus.h"
#include "proto/features.h"
#include "proto/frame.h"
#include "proto/stats.h"
#include "proto/wire_mesh.h"

#define ISM_COMPUTED_VERSION 7
/* The cache entry's extension ("<surface key>.mesh"). */
#define ISM_COMPUTED_EXT "mesh"

typedef struct ism_computed {
    char surface_key[65];
    bool empty;                /* no triangle with three distinct vertices */
    ism_mesh mesh;             /* positions, normals, triangles (owned) */
    ism_wire_mesh wire;        /* every attribute (owned; tri is mesh.tri, class is below) */
    uint8_t *vertex_class;     /* owned; NULL when the analysis had none */
    uint32_t *tri_cell;        /* owned, per triangle; NULL when no curves were requested */
    uint8_t *tri_sheet;        /* owned, per triangle; NULL when f has no double sheet */
    uint32_t *corner_at;       /* owned: the wire's corner normals (wire_mesh.h), NULL none */
    float *corner_normal;
    uint8_t *corner_locus;     /* owned: per corner normal, 1 at the singular locus; NULL none */
    ism_features features;     /* owned; features.locus is &locus, check NULL */
    ism_locus locus;           /* singular points and curves (what the glb draws) */
    char *features_json;       /* the features JSON (proto/features.h) */
    size_t features_len;
    char *stats_json;          /* the encoding-independent stats (ism_stats_surface_json) */
    size_t stats_len;
    double timings_ms[ISM_TIME_COUNT]; /* of the computation (encode and total left 0) */
} ism_computed;

void ism_computed_init(ism_computed *c);
void ism_computed_free(ism_computed *c);

/* The entry's bytes, appended to b. False when out of memory (b->failed). */
bool ism_computed_write(const ism_computed *c, ism_frame_builder *b);

/* Reads an entry into c (copies; data may go afterwards). False with a reason in why when the
 * bytes are not a valid entry of this version (c is then empty). */
bool ism_computed_read(const void *data, size_t len, ism_computed *c, char *why, size_t n);

/* A view of c's wire form with only the attributes in attrs (enum ism_attr bits). Points
 * into c: do not free it. */
void ism_computed_wire(const ism_computed *c, unsigned attrs, ism_wire_mesh *view);

#endif
