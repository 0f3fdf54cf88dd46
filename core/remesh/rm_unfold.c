/* rm_unfold.c — pleats: triangles turned over against their neighbours, facing the other
 * side of ∇f (the polygoniser's and the conformance's fold bands beside a double curve:
 * klein-bottle 69 turned edges, 34 after the flips and moves, which cannot mend them — a
 * move is refused while any triangle of the fan faces more than 60° from the fan's normal,
 * and a turned one always does). A free vertex whose fan has triangles facing both sides of
 * ∇f at it moves to the mean of its neighbours, within the tangent plane of f = 0, and Newton
 * puts it back on f = 0; the move is kept when fewer of its triangles face the minority side
 * (with ∇f at the new place), none is degenerate, and no centroid of the fan ends farther
 * from f = 0 than the mesh's farthest before the pass or the fan's own (rm_centroids_stay). */
#include "core/remesh/rm_pass.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>

/* The fans unfolded per vertex are at most this large (the polygoniser's have about 6). */
#define ISM_RM_UNFOLD_MAX_DEGREE 24
/* Newton may move the vertex at most this × the mean distance to its neighbours off its
 * tangent step (farther, it found another sheet: rm_relax.c's ISM_RM_PROJECT_MAX_REL). */
#define ISM_RM_UNFOLD_PROJECT_MAX 0.5

/* The fan's triangles that face the side of g (unit or not) the fewer of them face, with v
 * read at x; -1 when a triangle is degenerate there. */
static int minority(const rm_pass *p, uint32_t v, const double *x, const double g[3])
{
    const rm_mesh *r = &p->r;
    int up = 0, down = 0;
    for (uint32_t i = 0; i < r->count[v]; i++) {
        double n[3];
        if (!(rm_fan_cross(p, v, i, x, n) > 0))
            return -1;
        double s = ism_dot3(n, g);
        up += s > 0;
        down += s <= 0;
    }
    return up < down ? up : down;
}

/* The mean of v's neighbours (each triangle's next corner after v: each once in a closed
 * fan) and their mean distance from v. */
static double ring_mean(const rm_pass *p, uint32_t v, double mean[3])
{
    const rm_mesh *r = &p->r;
    const double *x = r->m->pos + 3 * (size_t)v;
    double dist = 0;
    mean[0] = mean[1] = mean[2] = 0;
    for (uint32_t i = 0; i < r->count[v]; i++) {
        uint32_t t = r->vt[r->start[v] + i];
        const double *q = r->m->pos + 3 * (size_t)r->m->tri[3 * t + (rm_corner(r->m, t, v) + 1) % 3];
        for (int k = 0; k < 3; k++)
            mean[k] += q[k] / r->count[v];
        dist += rm_dist(x, q) / r->count[v];
    }
    return dist;
}

/* Tries to unfold v's fan; true when v moved. */
static bool unfold_vertex(rm_pass *p, uint32_t v)
{
    const rm_mesh *r = &p->r;
    const double *pos = r->m->pos + 3 * (size_t)v, *n = p->normal + 3 * (size_t)v;
    int before = minority(p, v, pos, n);
    if (before <= 0)
        return false;
    double x[3], g[3], tangent[3];
    double scale = ring_mean(p, v, x);
    double d[3] = {x[0] - pos[0], x[1] - pos[1], x[2] - pos[2]}, dn = ism_dot3(d, n);
    for (int k = 0; k < 3; k++)
        x[k] = tangent[k] = pos[k] + d[k] - dn * n[k];
    if (!rm_project(p, x, scale, -1, g) ||
        !(rm_dist(x, tangent) <= ISM_RM_UNFOLD_PROJECT_MAX * scale))
        return false;
    int after = minority(p, v, x, g);
    if (after < 0 || after >= before || !rm_centroids_stay(p, v, x))
        return false;
    rm_commit_move(p, v, x, g);
    return true;
}

/* Marks in side[v] which sides of ∇f at v its triangles face (1: ∇f's, 2: the other): one
 * normal per triangle, where asking each fan would take three. */
static void mark_sides(const rm_pass *p, uint8_t *side)
{
    const ism_mesh *m = p->r.m;
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *v = m->tri + 3 * t;
        double n[3];
        if (p->r.dead[t] ||
            !(rm_cross(m->pos + 3 * (size_t)v[0], m->pos + 3 * (size_t)v[1],
                       m->pos + 3 * (size_t)v[2], n) > 0))
            continue;
        for (int k = 0; k < 3; k++)
            side[v[k]] |= ism_dot3(n, p->normal + 3 * (size_t)v[k]) > 0 ? 1 : 2;
    }
}

size_t rm_unfold_sweep(rm_pass *p)
{
    const rm_mesh *r = &p->r;
    uint8_t *side = calloc(r->m->nverts ? r->m->nverts : 1, 1);
    if (!side)
        return 0; /* no unfolding this round: the mesh is as valid as before */
    mark_sides(p, side);
    size_t moves = 0;
    for (size_t v = 0; v < r->m->nverts; v++)
        if (side[v] == 3 && !r->locked[v] && r->count[v] >= 3 &&
            r->count[v] <= ISM_RM_UNFOLD_MAX_DEGREE && unfold_vertex(p, (uint32_t)v))
            moves++;
    free(side);
    p->moves += moves;
    return moves;
}
