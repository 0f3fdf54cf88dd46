/* cell_types.h — the plain data the steps of a node's polygonisation pass to one another:
 * surface points (ism_fpoint), face lines (ism_fline), stitched loops (ism_loop), tile
 * boundary points and events (ism_bpoint, ism_fevent), the triangles a node emits
 * (ism_cell_out) and the per-thread counters (ism_cell_stats). Types only: the low-level
 * steps (face_lines, stitch, singular, triangulate, weld) include this, never cell.h. */
#ifndef ISM_CELL_TYPES_H
#define ISM_CELL_TYPES_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>

/* Where a surface point on a node's boundary came from (kept with the vertex for stats). */
enum ism_fpoint_flags {
    ISM_FP_ZERO = 1,       /* a lattice point where f is exactly 0 */
    ISM_FP_TOUCH = 2,      /* a double (tangent) root */
    ISM_FP_PAIR = 4,       /* one of two roots on a segment */
    ISM_FP_MANY = 8,       /* on a segment suspected of more than two roots */
    ISM_FP_INTERIOR = 16,  /* a polygon's centre (not on the node boundary) */
    ISM_FP_SINGULAR = 32,  /* an isolated singular point inside the node (see singular.h) */
    ISM_FP_CREASE = 64,    /* on a min/max crease, a = b = 0 (crease_split.h): either branch */
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
    bool ascending; /* the boundary's segment from here to the next point runs up its lattice
                       line (the segment's canonical direction: the tile's first two sides) */
    double p[3], f, g[3], gn; /* gn = |g| */
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
    uint64_t lifted_polygons, lifted_chords;
} ism_cell_stats;

#endif
