/* arr_types.h — the arrangement's vertices, edges, faces and curves (arrangement.h): data
 * only, shared by its driver and its files (arr_internal.h). */
#ifndef ISM_ARR_TYPES_H
#define ISM_ARR_TYPES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

enum ism_arr_vertex_type {
    ISM_ARR_CROSSING,  /* curves of two or more functions meet */
    ISM_ARR_BRANCH,    /* one function's curve meets itself (degree ≥ 3) */
    ISM_ARR_END,       /* a curve ends (the mesh's border: the box) */
    ISM_ARR_LOOP,      /* the chosen point of a closed curve that meets nothing */
    ISM_ARR_DOUBLE_CURVE,   /* curves meet a double curve of the surface (the vertex ends a
                               mesh edge of three or more triangles) and end there */
    ISM_ARR_SINGULAR_POINT, /* curves meet a singular point of the locus (node, cusp, pinch,
                               triple point, ...) and end there */
    ISM_ARR_VERTEX_TYPE_COUNT
};

typedef struct ism_arr_vertex {
    uint32_t v;        /* mesh vertex */
    int degree;        /* arcs leaving it */
    int type;          /* enum ism_arr_vertex_type */
    int point;         /* ISM_ARR_SINGULAR_POINT: index into the locus's points; else -1 */
} ism_arr_vertex;

typedef struct ism_arr_edge {
    uint32_t from, to; /* arrangement vertices */
    uint32_t curve;    /* index into curves */
    uint32_t fn;       /* the cutting function */
    double length;
    size_t first, count; /* the mesh vertices along it: chain[first .. first+count) */
} ism_arr_edge;

typedef struct ism_arr_face {
    size_t first, ntris; /* its triangles in the reordered mesh */
    double area;
    long euler;          /* V − E + T of its closed triangles (disk 1, annulus 0) */
    long euler_open;     /* the same without the elements on curves (sums to χ): a vertex
                            off the curves shared by several faces (a node joining two
                            cones) counts in the first of them only */
    uint32_t boundary;   /* boundary cycles (connected parts of its border) */
    uint32_t component;  /* the mesh component it lies in */
} ism_arr_face;

typedef struct ism_arr_curve {
    uint32_t fn;
    bool closed;         /* it ends nowhere: no END, DOUBLE_CURVE or SINGULAR_POINT vertex */
    double length;
    size_t nedges;
} ism_arr_curve;

typedef struct ism_arrangement {
    ism_arr_vertex *vertices;
    ism_arr_edge *edges;
    ism_arr_face *faces;
    ism_arr_curve *curves;
    uint32_t *chain;
    uint32_t *tri_face;    /* per triangle of the mesh: its face (non-decreasing) */
    size_t nvertices, nedges, nfaces, ncurves, nchain;
    size_t ncomponents;
    long euler_mesh;       /* V − E + T of the mesh */
    long euler_arr;        /* V − E + Σ face euler_open of the arrangement */
    bool euler_ok;         /* the two agree in every component */
} ism_arrangement;

#endif
