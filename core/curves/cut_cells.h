/* cut_cells.h — where the cut's per-function work happens: the mesh's triangles binned in a
 * uniform grid by centroid, each cell with the bounds of its triangles' vertices, so one
 * interval evaluation of g over a cell's bounds tells that none of its triangles is crossed.
 * Per function only the crossed cells and the ring of cells round them (the triangles the
 * cut splits and their corners' stars: the tangency seeds' links) are listed, instead of a
 * pass over the whole mesh per function. Not public. */
#ifndef ISM_CUT_CELLS_H
#define ISM_CUT_CELLS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct cut_cell {
    uint32_t *tri;  /* the triangles placed in it */
    size_t n, cap;
    double box[6];  /* bounds of their vertices (lo xyz, hi xyz) */
    uint32_t block; /* the block it belongs to */
    uint8_t ring;   /* for the current function: 1 crossed, 2 the ring round it */
} cut_cell;

typedef struct cut_block {
    uint32_t *cells;  /* its cells with triangles */
    size_t n, cap;
    double box[6];    /* the union of their bounds */
} cut_block;

typedef struct cut_cells {
    bool valid;         /* false: rebuilt before the next function (after a crease cut or a
                           merge renumbered the triangles) */
    cut_cell *cell;
    size_t ncell;
    size_t built_tris;  /* triangles when the grid was built */
    int dim[3];
    double org[3], h;   /* grid origin and cell side */
    double inv_h;       /* 1 / h */
    cut_block *block;   /* blocks of cells (cut_cells.c), tried before their cells */
    size_t nblock;
    int bdim[3];
    int over;           /* cells a cell's bounds reach past its grid box (ring search) */
    uint32_t *tcell;    /* per triangle: its cell */
    size_t cap_tcell;
    uint32_t *tris;     /* the current function's triangles, in the cells it may cross
                           (ascending) */
    size_t ntris, cap_tris;
    uint32_t *ring_tris; /* the triangles of the ring round them (ascending): g has one
                            sign at all their corners (the cells' intervals say so); they
                            complete the stars of the crossed triangles' corners */
    size_t nring, cap_ring;
    size_t ncrossed;    /* the first ncrossed cells of list are the crossed ones */
    uint32_t *verts;    /* the vertices of tris, then those of the ring's triangles whose g
                           was asked for (cut_cells_near_values) */
    size_t nverts, cap_verts;
    uint32_t *vstamp;   /* per vertex: the function + 1 whose g it holds in gv / sg */
    size_t cap_vstamp;
    uint32_t *list;     /* scratch: cells of the current function */
    size_t nlist, cap_list;
    uint64_t *bits;     /* scratch: one bit per triangle, the listed ones */
    size_t cap_bits;
} cut_cells;

#endif
