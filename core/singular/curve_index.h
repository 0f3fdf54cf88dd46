/* curve_index.h — where the traced curves are, relative to the search's candidate boxes: a
 * grid over the boxes (sorted cell keys, built once), and per box the traced segments that
 * pass through it. It answers the two questions tracing asks: which boxes does a new segment
 * explain (they become ISM_LBOX_USED), and does a seed lie on a curve already traced. */
#ifndef ISM_CURVE_INDEX_H
#define ISM_CURVE_INDEX_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/singular/locus.h"

typedef struct ism_cindex {
    ism_lbox *boxes;       /* the locus's boxes (flags are updated in place) */
    size_t nboxes;
    double origin[3], cell;/* grid: cell ≥ every box's side */
    struct ism_cindex_key { uint64_t key; uint32_t box; } *keys; /* by the cell of the box's
                                                                     centre, sorted */
    size_t nkeys;
    uint32_t *stamp;       /* per box: last query that visited it (no double visits) */
    uint32_t query;
    int32_t *head;         /* per box: first link of its segment list, -1 if none */
    struct ism_cindex_link { uint32_t seg; int32_t next; } *links;
    size_t nlinks, cap_links;
    double (*segs)[6];     /* traced segments a→b */
    size_t nsegs, cap_segs;
} ism_cindex;

/* Builds the grid over boxes[0..n) (n < 2^31) inside the search box. False when out of
 * memory. */
bool ism_cindex_build(ism_cindex *x, ism_lbox *boxes, size_t n, const double box[6],
                      double cell);

void ism_cindex_free(ism_cindex *x);

/* Records the segment a→b in every box it passes through (grown by delta), and marks USED
 * the boxes it passes through and the boxes whose projected point q lies within delta of
 * it. False when out of memory. */
bool ism_cindex_add_segment(ism_cindex *x, const double a[3], const double b[3], double delta);

/* Marks USED the boxes within r of p (r at most the grid cell). */
void ism_cindex_mark_ball(ism_cindex *x, const double p[3], double r);

/* True when a recorded segment passes within delta (at most the grid cell) of p. */
bool ism_cindex_near_segment(ism_cindex *x, const double p[3], double delta);

#endif
