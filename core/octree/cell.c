/* cell.c — CreatePolygons for one plotting node: the lines of every tile of its six faces
 * (finer neighbours' tiles where they exist — crack repair), stitched into polygons, each
 * polygon triangulated; one-edge polygons are kept as segments. */
#include "core/octree/cell.h"
#include "core/octree/stitch.h"
#include "core/octree/triangulate.h"

#include <stdlib.h>
#include <string.h>

typedef struct face_walk {
    ism_cell_ctx *cx;
    size_t tiles;
    bool ok;
} face_walk;

static bool on_tile(void *ctx, const ism_tile *tile)
{
    face_walk *w = ctx;
    w->tiles++;
    if (!ism_tile_lines(w->cx, tile))
        w->ok = false;
    return w->ok;
}

bool ism_cell_polygonise(ism_cell_ctx *cx, int32_t node, ism_cell_out *out)
{
    cx->lines.n = 0;
    for (int axis = 0; axis < 3; axis++)
        for (int side = 0; side < 2; side++) {
            face_walk w = {cx, 0, true};
            size_t before = cx->lines.n;
            ism_octree_face_tiles(cx->tree, node, axis, side, on_tile, &w);
            if (!w.ok)
                return false;
            if (w.tiles > 1 && cx->lines.n > before)
                cx->stats.crack_tiles++;
        }
    if (cx->lines.n == 0)
        return true;
    if (!ism_stitch(&cx->lines, &cx->loops))
        return false;

    const ism_node *nd = &cx->tree->nodes[node];
    double reach = 0.5 * ism_grid_cell_size(&cx->tree->grid, nd->level);
    size_t polygons = 0;
    for (size_t k = 0; k < cx->loops.nloops; k++) {
        const ism_loop *lp = &cx->loops.loops[k];
        const ism_fpoint *p = cx->loops.pts + lp->first;
        if (!lp->closed)
            cx->stats.open_chains++;
        if (lp->n == 2) {
            cx->stats.degenerate_polygons++;
            if (!ism_cell_out_segment(out, &p[0], &p[1]))
                return false;
            continue;
        }
        if (lp->n < 2)
            continue;
        polygons++;
        if (!ism_triangulate_loop(&cx->s, p, lp->n, reach, out))
            return false;
    }
    cx->stats.polygons += polygons;
    if (polygons == 2)
        cx->stats.two_polygon_nodes++;
    else if (polygons > 2)
        cx->stats.many_polygon_nodes++;
    return true;
}

void ism_cell_ctx_free(ism_cell_ctx *cx)
{
    ism_coords_free(&cx->coords);
    free(cx->bp);
    free(cx->ev);
    free(cx->lines.v);
    ism_loops_free(&cx->loops);
    cx->bp = NULL;
    cx->ev = NULL;
    cx->lines.v = NULL;
}

void ism_cell_out_free(ism_cell_out *o)
{
    free(o->verts);
    free(o->tris);
    free(o->segs);
    memset(o, 0, sizeof *o);
}
