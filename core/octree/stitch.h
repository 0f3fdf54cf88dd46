/* stitch.h — StitchPolygon: a node's face lines joined into polygons (closed loops of
 * surface points), keeping lines shared by two sheets apart so each sheet gets its own
 * polygon. */
#ifndef ISM_STITCH_H
#define ISM_STITCH_H

#include <stdbool.h>
#include "core/octree/cell_types.h"

/* Replaces out's contents with the polygons made from the lines l. */
bool ism_stitch(const ism_flines *l, ism_loops *out);
void ism_loops_free(ism_loops *o);

#endif
