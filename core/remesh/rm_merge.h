/* rm_merge.h — merging a vertex into a neighbour across a manifold edge (rm_merge.c), the
 * step every edge collapse shares (the quality pass's needle collapses, rm_collapse.c, and
 * the simplification, sp_collapse.c): finding the two triangles on the edge, the link
 * condition that keeps the topology, and the incidence update. Where the kept vertex ends up
 * and whether the merge is worth it are the callers' decisions. */
#ifndef ISM_RM_MERGE_H
#define ISM_RM_MERGE_H

#include "core/remesh/rm_mesh.h"

/* A removed vertex's triangles, and the kept one's after the merge, are at most this many:
 * it bounds the fans held on the stack (the polygoniser's vertices have about 6). */
#define ISM_RM_MERGE_MAX_DEGREE 24

/* A candidate: v merged into w, t1 = (v, w, c) and t2 = (w, v, d) removed. */
typedef struct rm_merge {
    uint32_t v, w, t1, t2, c, d;
    double after; /* the caller's score (the new fan's smallest sine) */
    bool along;   /* the caller's: each new triangle held to its own normal (a crease
                     merge, or a free crowding pair: rm_collapse.c) */
} rm_merge;

/* Fills g for merging v into w when vw is an oriented manifold edge, neither is gone, v is
 * not locked, has from 3 to max_degree triangles, and the merged fan has at most max_degree
 * (at most ISM_RM_MERGE_MAX_DEGREE); false otherwise. */
bool rm_merge_find(const rm_mesh *r, uint32_t v, uint32_t w, uint32_t max_degree, rm_merge *g);
/* The same whether v is locked or not (a crease vertex merged along its crease: the caller
 * has checked that the crease allows it). */
bool rm_merge_find_any(const rm_mesh *r, uint32_t v, uint32_t w, uint32_t max_degree,
                       rm_merge *g);

/* rm_merge_find with no limit on w's degree (only v's, ISM_RM_MERGE_MAX_DEGREE: its fan is
 * held on the stack; w's slot grows): a singular point's vertex taking a tube's rings
 * (rm_horn.c). w may then have more than ISM_RM_MERGE_MAX_DEGREE triangles: a later
 * rm_merge_neighbours(w) sees only its first ISM_RM_MERGE_MAX_DEGREE, and rm_merge_link_ok
 * refuses w as the vertex merged away; safe while rm_horn_tips is the pass's last step. */
bool rm_merge_find_into(const rm_mesh *r, uint32_t v, uint32_t w, rm_merge *g);

/* v's distinct neighbours into nb (room for 2 × ISM_RM_MERGE_MAX_DEGREE, v having at most
 * ISM_RM_MERGE_MAX_DEGREE triangles); returns how many. */
int rm_merge_neighbours(const rm_mesh *r, uint32_t v, uint32_t *nb);

/* The link condition: no neighbour of w other than v, c, d is a neighbour of v (counted over
 * every sheet at w), and where v has three triangles, w has none on c and d already. Then
 * the merge keeps χ, components, cones and boundary loops. g as rm_merge_find(_any) or
 * rm_merge_find_into fills it (false when v has more than ISM_RM_MERGE_MAX_DEGREE
 * triangles). */
bool rm_merge_link_ok(const rm_mesh *r, const rm_merge *g);

/* The corners of triangle t with v's corner read at x (x may be v's own position). */
void rm_merge_corners(const rm_mesh *r, uint32_t t, uint32_t v, const double *x,
                      const double *q[3]);

/* The triangle across edge {a, b} from triangle t, or UINT32_MAX when ab is no oriented
 * manifold edge. */
uint32_t rm_merge_across(const rm_mesh *r, uint32_t a, uint32_t b, uint32_t t);

/* Merges g->v into g->w: t1 and t2 die, v's other triangles take w (copied to fan, at most
 * ISM_RM_MERGE_MAX_DEGREE, *nfan how many), v is gone and locked. False when out of memory
 * (nothing changed). */
bool rm_merge_apply(rm_mesh *r, const rm_merge *g, uint32_t *fan, uint32_t *nfan);

/* Undoes rm_merge_apply(r, g, fan, nfan) when nothing has changed since (or every later merge
 * has been undone, last first): t1 and t2 live again on w, c and d, the fan's triangles take v
 * back, v is neither gone nor locked (rm_merge_find_into's v was free). v's slot still holds
 * its triangles (apply only empties its count); each slot a triangle returns to had it
 * before, so has the room. */
void rm_merge_unapply(rm_mesh *r, const rm_merge *g, const uint32_t *fan, uint32_t nfan);

#endif
