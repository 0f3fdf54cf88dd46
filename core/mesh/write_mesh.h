/* write_mesh.h — the mesh file writers (binary little-endian PLY with normals, OBJ, binary STL).
 * They write through a caller's callback, so the same code fills a memory buffer, a file or
 * a socket-free pipe; a short write stops the writer, which then returns false. */
#ifndef ISM_WRITE_MESH_H
#define ISM_WRITE_MESH_H

#include <stddef.h>
#include <stdbool.h>
#include <stdint.h>
#include "core/mesh/mesh.h"

/* Writes n bytes from p; returns how many were written (fewer than n means failure). */
typedef size_t (*ism_write_fn)(void *ctx, const void *p, size_t n);

/* PLY 1.0, binary little endian: float x y z nx ny nz per vertex, then faces as a uchar
 * count and three int indices. An empty mesh gives a valid file with zero elements. */
bool ism_write_ply(const ism_mesh *m, ism_write_fn write, void *ctx);

/* Wavefront OBJ: `v`, `vn` (one per vertex) and `f a//a b//b c//c` lines, 1-based indices,
 * coordinates with 9 significant digits (float precision). */
bool ism_write_obj(const ism_mesh *m, ism_write_fn write, void *ctx);

/* Corners with a normal of their own (a crease's sides, the singular locus's sheets): at[j]
 * is the corner 3 t + k (ascending), normal[3 which[j] ..] its unit normal; several corners
 * may share one normal (one half-sheet at a vertex). */
typedef struct ism_obj_corner_normals {
    size_t n;
    const uint32_t *at;
    const float *normal;
    const uint32_t *which;
    size_t nnormals;
} ism_obj_corner_normals;

/* As ism_write_obj, with cn's nnormals normals written after the vertices' `vn` lines and
 * used by those corners (`f a//nA ...`); cn NULL or empty writes ism_write_obj's file. */
bool ism_write_obj_corners(const ism_mesh *m, const ism_obj_corner_normals *cn,
                           ism_write_fn write, void *ctx);

/* Binary STL: 80-byte header, triangle count, then per triangle its unit facet normal
 * (from the vertices' winding; 0 for a zero-area triangle), three corners and a zero
 * attribute word. Fails for more than UINT32_MAX triangles. */
bool ism_write_stl(const ism_mesh *m, ism_write_fn write, void *ctx);

/* Exact sizes in bytes of the PLY and STL files ism_write_ply / ism_write_stl produce. */
size_t ism_ply_size(const ism_mesh *m);
size_t ism_stl_size(const ism_mesh *m);

#endif
