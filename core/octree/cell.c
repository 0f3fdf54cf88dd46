/* cell.c — CreatePolygons for one plotting node: the lines of every tile of its six faces
 * (finer neighbours' tiles where they exist — crack repair), stitched into polygons, each
 * polygon triangulated; one-edge polygons are kept as segments. */
#include "core/octree/cell.h"
#include "core/octree/crease_split.h"
#include "core/octree/face_lines.h"
#include "core/octree/face_flat.h"
#include "core/octree/singular.h"
#include "core/octree/stitch.h"
#include "core/octree/triangulate.h"
#include "core/util/grow.h"

#include <stdlib.h>
#include <string.h>

typedef struct face_walk {
    ism_cell_ctx *cx;
    ism_cell_out *out;
    bool owner;           /* this node emits the face's planar pieces (see below) */
    size_t tiles;
    bool ok;
} face_walk;

/* How far off the tile f is sampled on either side, as a fraction of the tile's smaller
 * side: inside both nodes that share the tile (each at least as large as the tile). */
#define ZERO_TILE_PROBE 0.25

/* Does f take opposite signs just off the tile on its two sides? A plane of the surface on
 * the lattice (x = 0 of xyz) does; a double sheet (x² = 0: no sign change) does not, and is
 * left to core/singular's double-sheet stage, which records it as such. */
static bool sign_changes_across(ism_cell_ctx *cx, const ism_tile *t)
{
    const ism_grid *g = &cx->tree->grid;
    int u = ism_axis_next(t->axis), v = ism_axis_prev(t->axis);
    double c[3];
    c[t->axis] = ism_grid_coord(g, t->axis, t->plane);
    c[u] = 0.5 * (ism_grid_coord(g, u, t->u0) + ism_grid_coord(g, u, t->u1));
    c[v] = 0.5 * (ism_grid_coord(g, v, t->v0) + ism_grid_coord(g, v, t->v1));
    double du = ism_grid_coord(g, u, t->u1) - ism_grid_coord(g, u, t->u0);
    double dv = ism_grid_coord(g, v, t->v1) - ism_grid_coord(g, v, t->v0);
    double d = ZERO_TILE_PROBE * (du < dv ? du : dv);
    double a[3] = {c[0], c[1], c[2]}, b[3] = {c[0], c[1], c[2]};
    a[t->axis] -= d;
    b[t->axis] += d;
    double fa = ism_sample_f(&cx->s, a), fb = ism_sample_f(&cx->s, b);
    return (fa < 0 && fb > 0) || (fa > 0 && fb < 0);
}

/* A tile lying in f = 0 is one polygon of the surface, emitted once: by the node below
 * it along its axis (or above it on the search box's lower boundary) — unless f keeps its
 * sign across it (a double sheet, not the polygoniser's). */
static bool emit_zero_tile(face_walk *w, const ism_tile *tile)
{
    ism_cell_ctx *cx = w->cx;
    if (!ism_grow((void **)&cx->zero, &cx->cap_zero, cx->nzero + 1, sizeof *cx->zero, 8))
        return false;
    cx->zero[cx->nzero++] = *tile;
    if (!w->owner || !sign_changes_across(cx, tile))
        return true;
    ism_fpoint *pts = malloc(cx->nbp * sizeof *pts);
    if (!pts)
        return false;
    for (size_t i = 0; i < cx->nbp; i++) {
        memcpy(pts[i].p, cx->bp[i].p, sizeof pts[i].p);
        memcpy(pts[i].g, cx->bp[i].g, sizeof pts[i].g);
        pts[i].flags = ISM_FP_ZERO;
    }
    double reach = 0;
    bool ok = ism_triangulate_loop(&cx->s, pts, cx->nbp, reach, NULL, 0, w->out);
    free(pts);
    cx->stats.polygons++;
    return ok;
}

static bool on_tile(face_walk *w, const ism_node_tile *nt)
{
    w->tiles++;
    if (!ism_tile_lines(w->cx, nt) || (w->cx->zero_tile && !emit_zero_tile(w, &nt->t)))
        w->ok = false;
    return w->ok;
}

/* gather_tiles' list: the context and where each face's tiles start. */
typedef struct tile_gather {
    ism_cell_ctx *cx;
    size_t *first;
    int face; /* faces before this one have their start set */
} tile_gather;

/* Keeps tile (of the node's face `face`, ism_octree_node_tiles' order), keyed. */
static bool keep_tile(void *ctx, int face, const ism_tile *tile)
{
    tile_gather *tg = ctx;
    ism_cell_ctx *cx = tg->cx;
    for (; tg->face <= face; tg->face++)
        tg->first[tg->face] = cx->ntiles;
    if (!ism_grow((void **)&cx->tiles, &cx->cap_tiles, cx->ntiles + 1, sizeof *cx->tiles, 32))
        return false;
    ism_node_tile_set(&cx->tiles[cx->ntiles++], tile);
    return true;
}

/* Is tile t the whole face of a node s lattice steps wide (then its corners are the node's)?
 * A face's tiles are the node's own face or finer leaves' faces (ism_octree_face_tiles never
 * emits a coarser neighbour's face), so a tile s wide on the node's face is that face. */
static bool whole_face(const ism_tile *t, int32_t s)
{
    return t->u1 - t->u0 == s && t->v1 - t->v0 == s;
}

/* The tiles of the node's six faces into cx->tiles (found in one pass:
 * ism_octree_node_tiles), face f's from first[f] to first[f + 1], each keyed as it is kept
 * (ism_node_tile_set) and asked for from memory (ism_tile_prefetch) before any is walked: the
 * node's 8 corners once, the corners of finer tiles with them. */
static bool gather_tiles(ism_cell_ctx *cx, int32_t node, size_t first[7])
{
    cx->ntiles = 0;
    tile_gather tg = {cx, first, 0};
    if (!ism_octree_node_tiles(cx->tree, cx->parent, node, &cx->nbs, keep_tile, &tg))
        return false;
    for (; tg.face <= 6; tg.face++)
        first[tg.face] = cx->ntiles;
    if (!cx->ntiles)
        return true; /* no tile: no corner will be looked up */
    const ism_node *nd = &cx->tree->nodes[node];
    int32_t s = ism_grid_cell_steps(&cx->tree->grid, nd->level);
    for (int k = 0; k < 8; k++) {
        int32_t q[3] = {nd->org[0] + (k & 1 ? s : 0), nd->org[1] + (k & 2 ? s : 0),
                        nd->org[2] + (k & 4 ? s : 0)};
        ism_lattice_prefetch(cx, q);
    }
    for (size_t i = 0; i < cx->ntiles; i++)
        ism_tile_prefetch(cx, &cx->tiles[i], !whole_face(&cx->tiles[i].t, s));
    return true;
}

/* Is the segment ab on the boundary of tile t (world coordinates)? */
static bool on_tile_boundary(const ism_grid *g, const ism_tile *t, const double a[3],
                             const double b[3])
{
    int u = ism_axis_next(t->axis), v = ism_axis_prev(t->axis);
    double w = ism_grid_coord(g, t->axis, t->plane);
    double u0 = ism_grid_coord(g, u, t->u0), u1 = ism_grid_coord(g, u, t->u1);
    double v0 = ism_grid_coord(g, v, t->v0), v1 = ism_grid_coord(g, v, t->v1);
    if (a[t->axis] != w || b[t->axis] != w)
        return false;
    for (int k = 0; k < 2; k++) {
        const double *p = k ? b : a;
        if (p[u] < u0 || p[u] > u1 || p[v] < v0 || p[v] > v1)
            return false;
    }
    return (a[u] == b[u] && (a[u] == u0 || a[u] == u1)) ||
           (a[v] == b[v] && (a[v] == v0 || a[v] == v1));
}

/* Does p lie in tile t (its plane, within its extent; world coordinates)? */
static bool in_tile(const ism_grid *g, const ism_tile *t, const double p[3])
{
    int u = ism_axis_next(t->axis), v = ism_axis_prev(t->axis);
    return p[t->axis] == ism_grid_coord(g, t->axis, t->plane) &&
           p[u] >= ism_grid_coord(g, u, t->u0) && p[u] <= ism_grid_coord(g, u, t->u1) &&
           p[v] >= ism_grid_coord(g, v, t->v0) && p[v] <= ism_grid_coord(g, v, t->v1);
}

static bool in_zero_tile(const ism_cell_ctx *cx, const double p[3])
{
    for (size_t z = 0; z < cx->nzero; z++)
        if (in_tile(&cx->tree->grid, &cx->zero[z], p))
            return true;
    return false;
}

/* Is the open chain p[0 .. n) closed across the node's zero tiles (f = 0 on a whole tile,
 * emitted as a polygon of its own)? A sheet crossing a face that lies in another sheet
 * (nine planes in a lattice box: x = 0 is a lattice plane) meets the tile's boundary at two
 * zero lattice points, and the tile's walk emits no line across it (only the tile): the
 * chain's closing side lies in the tile, or in two zero tiles meeting at the node's edge
 * where two such planes cross. It is triangulated as any chain; only the count of open
 * chains (lines that could not be closed) leaves it out — nine planes ±1.5 at depth 3:
 * 1464 -> 0. */
static bool closed_by_zero_tiles(const ism_cell_ctx *cx, const ism_fpoint *p, size_t n)
{
    return n >= 2 && in_zero_tile(cx, p[0].p) && in_zero_tile(cx, p[n - 1].p);
}

/* Zero edges along a planar piece of the surface belong to that piece, not to a
 * one-edge polygon of their own. */
static void drop_edges_of_zero_tiles(ism_cell_ctx *cx)
{
    size_t kept = 0;
    for (size_t i = 0; i < cx->lines.n; i++) {
        ism_fline *l = &cx->lines.v[i];
        bool covered = false;
        for (size_t z = 0; z < cx->nzero && l->kind == ISM_LINE_EDGE && !covered; z++)
            covered = on_tile_boundary(&cx->tree->grid, &cx->zero[z], l->a.p, l->b.p);
        if (!covered)
            cx->lines.v[kept++] = *l;
    }
    cx->lines.n = kept;
}

/* Does this node emit what lies in its face (2 × axis + side) and nowhere else: its upper
 * faces, and its lower faces on the search box's lower boundary (emit_zero_tile's rule)? */
static bool owns_face(const ism_node *nd, int face)
{
    return face % 2 == 1 || nd->org[face / 2] == 0;
}

/* A polygon lying in one of the node's faces (face_flat.h): fanned from the surface point
 * above it on this node's side; with none there, emitted flat by the face's owner only. */
static bool face_polygon(ism_cell_ctx *cx, const ism_node *nd, const ism_fpoint *p, size_t n,
                         int face, double reach, const double box[6], ism_cell_out *out)
{
    ism_fpoint top;
    if (ism_lift_point(&cx->s, p, n, box, face, &top)) {
        cx->stats.lifted_polygons++;
        return ism_triangulate_tent(p, n, &top, out);
    }
    if (!owns_face(nd, face))
        return true;
    return ism_triangulate_loop(&cx->s, p, n, reach, box, cx->max_error, out);
}

bool ism_cell_polygonise(ism_cell_ctx *cx, int32_t node, ism_cell_out *out)
{
    cx->lines.n = 0;
    cx->nzero = 0;
    const ism_node *nd = &cx->tree->nodes[node];
    if (nd->flags & ISM_NODE_ZERO_FREE)
        return true; /* no tile of its faces yields an event (octree.h) */
    size_t first[7];
    if (!gather_tiles(cx, node, first))
        return false;
    for (int face = 0; face < 6; face++) {
        int axis = face / 2, side = face % 2;
        face_walk w = {cx, out, side == 1 || nd->org[axis] == 0, 0, true};
        size_t before = cx->lines.n;
        for (size_t i = first[face]; i < first[face + 1] && w.ok; i++)
            on_tile(&w, &cx->tiles[i]);
        if (!w.ok)
            return false;
        if (w.tiles > 1 && cx->lines.n > before)
            cx->stats.crack_tiles++;
    }
    if (cx->nzero)
        drop_edges_of_zero_tiles(cx);
    if (cx->lines.n == 0)
        return true;
    if (!ism_stitch(&cx->lines, &cx->loops))
        return false;

    double reach = 0.5 * ism_grid_cell_size(&cx->tree->grid, nd->level);
    double box[6]; /* the node: lo xyz, hi xyz */
    int32_t steps = ism_grid_cell_steps(&cx->tree->grid, nd->level);
    for (int a = 0; a < 3; a++) {
        box[a] = ism_grid_coord(&cx->tree->grid, a, nd->org[a]);
        box[3 + a] = ism_grid_coord(&cx->tree->grid, a, nd->org[a] + steps);
    }
    ism_fpoint apex;
    bool has_apex = false;
    if (nd->flags & ISM_NODE_UNRESOLVED) {
        has_apex = ism_find_singular_point(&cx->s, box, box + 3, &apex);
        cx->stats.singular_points += has_apex;
    }
    size_t polygons = 0;
    for (size_t k = 0; k < cx->loops.nloops; k++) {
        const ism_loop *lp = &cx->loops.loops[k];
        const ism_fpoint *p = cx->loops.pts + lp->first;
        if (!lp->closed && !closed_by_zero_tiles(cx, p, lp->n))
            cx->stats.open_chains++;
        if (has_apex && lp->n >= 3) {
            polygons++;
            if (!ism_triangulate_fan(p, lp->n, &apex, out))
                return false;
            continue;
        }
        if (lp->n == 2) {
            cx->stats.degenerate_polygons++;
            if (!ism_cell_out_segment(out, &p[0], &p[1]))
                return false;
            continue;
        }
        if (lp->n < 2)
            continue;
        polygons++;
        int face = ism_face_plane(box, p, lp->n);
        if (face >= 0 && !face_polygon(cx, nd, p, lp->n, face, reach, box, out))
            return false;
        if (face < 0) {
            bool cut = false;
            if (cx->cut_creases &&
                !ism_crease_cut_loop(&cx->s, p, lp->n, reach, box, cx->max_error, out, &cut))
                return false;
            if (!cut && !ism_triangulate_loop(&cx->s, p, lp->n, reach, box, cx->max_error, out))
                return false;
        }
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
    free(cx->bp);
    free(cx->ev);
    free(cx->lines.v);
    ism_loops_free(&cx->loops);
    free(cx->zero);
    free(cx->tiles);
    free(cx->gap);
    cx->gap = NULL;
    cx->zero = NULL;
    cx->tiles = NULL;
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
