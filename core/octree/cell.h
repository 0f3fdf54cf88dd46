/* cell.h — the polygonisation of one plotting node: the per-thread context shared by the
 * face-line, stitching and triangulation steps, the face lines themselves, and the
 * polygons and triangles a node emits. */
#ifndef ISM_CELL_H
#define ISM_CELL_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/octree/breaks.h"
#include "core/octree/cell_cache.h"
#include "core/octree/edge_roots.h"
#include "core/octree/octree.h"
#include "core/octree/sampler.h"

/* Where a surface point on a node's boundary came from (kept with the vertex for stats). */
enum ism_fpoint_flags {
    ISM_FP_ZERO = 1,       /* a lattice point where f is exactly 0 */
    ISM_FP_TOUCH = 2,      /* a double (tangent) root */
    ISM_FP_PAIR = 4,       /* one of two roots on a segment */
    ISM_FP_MANY = 8,       /* on a segment suspected of more than two roots */
    ISM_FP_INTERIOR = 16,  /* a polygon's centre (not on the node boundary) */
    ISM_FP_SINGULAR = 32,  /* an isolated singular point inside the node (see singular.h) */
};

typedef struct ism_fpoint {
    double p[3];
    double g[3];           /* ∇f at p */
    uint8_t flags;
} ism_fpoint;

enum ism_line_kind {
    ISM_LINE_REGULAR = 0,  /* belongs to one polygon (paper's `line`) */
    ISM_LINE_DOUBLE = 1,   /* self-intersection on the face: two polygons (`nonManLine`) */
    ISM_LINE_EDGE = 2,     /* f = 0 along a lattice segment (a double line on an edge) */
};

typedef struct ism_fline {
    ism_fpoint a, b;
    uint8_t kind;
} ism_fline;

typedef struct ism_flines {
    ism_fline *v;
    size_t n, cap;
} ism_flines;

/* Polygons made by stitching: loops of surface points. */
typedef struct ism_loop {
    size_t first, n;   /* points pts[first .. first + n) */
    bool closed;       /* false: an open chain (lines that could not be closed) */
} ism_loop;

typedef struct ism_loops {
    ism_fpoint *pts;
    size_t npts, cap_pts;
    ism_loop *loops;
    size_t nloops, cap_loops;
} ism_loops;

/* One lattice point of a tile's boundary. */
typedef struct ism_bpoint {
    int32_t ip[3];
    double p[3], f, g[3];
} ism_bpoint;

/* A surface point on a tile's boundary, with the sign of f just before and after it
 * (walking the boundary): +1, -1, or 0 along a segment where f vanishes. */
typedef struct ism_fevent {
    ism_fpoint pt;
    int before, after;
    int seg; /* the boundary segment it lies on: from bp[seg] to bp[seg + 1] */
} ism_fevent;

/* The triangles and degenerate polygons one or more nodes emit, before welding. */
typedef struct ism_cell_out {
    ism_fpoint *verts;
    size_t nverts, cap_verts;
    uint32_t *tris;        /* local indices, 3 per triangle */
    size_t ntris, cap_tris;
    uint32_t *segs;        /* one-edge (degenerate) polygons, 2 local indices each */
    size_t nsegs, cap_segs;
} ism_cell_out;

typedef struct ism_cell_stats {
    uint64_t polygons, two_polygon_nodes, many_polygon_nodes, degenerate_polygons;
    uint64_t double_lines, open_chains, crossed_faces, crack_tiles, singular_points;
} ism_cell_stats;

typedef struct ism_cell_ctx {
    ism_sampler s;
    const ism_octree *tree;
    const ism_breaks *breaks;
    ism_root_params roots;
    double stitch_tol;        /* two roots closer than this × segment length are one */
    /* scratch, reused from node to node */
    ism_coords coords;
    ism_bpoint *bp;
    size_t nbp, cap_bp;
    ism_fevent *ev;
    size_t nev, cap_ev;
    ism_flines lines;
    ism_loops loops;
    ism_cell_cache cache;     /* must be initialised (ism_cell_cache_init) */
    bool zero_tile;           /* set by ism_tile_lines: f vanishes on the whole tile */
    ism_tile *zero;           /* the current node's tiles lying in f = 0 */
    size_t nzero, cap_zero;
    ism_cell_stats stats;
} ism_cell_ctx;

void ism_cell_ctx_free(ism_cell_ctx *cx);

bool ism_flines_push(ism_flines *l, const ism_fpoint *a, const ism_fpoint *b, int kind);

/* Appends to cx->lines the lines of f = 0 on one tile (a face or part of a face). When f
 * vanishes on the whole tile (a plane of the surface lying in the lattice), sets
 * cx->zero_tile, leaves cx->bp holding its boundary and adds no lines. */
bool ism_tile_lines(ism_cell_ctx *cx, const ism_tile *tile);

/* Polygonises leaf `node`: face lines of all its tiles, stitched into polygons,
 * triangulated into out. False only when out of memory. */
bool ism_cell_polygonise(ism_cell_ctx *cx, int32_t node, ism_cell_out *out);

void ism_cell_out_free(ism_cell_out *o);

#endif
