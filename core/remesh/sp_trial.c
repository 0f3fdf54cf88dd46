/* sp_trial.c — the snapshot a tried collapse is undone from, and the ring's settling after
 * it (sp_trial.h). */
#include "core/remesh/sp_trial.h"
#include "core/remesh/rm_bound.h"
#include "core/remesh/sp_place.h"

#include <string.h>

static bool take_slot(const rm_mesh *r, uint32_t v, sp_slot *s)
{
    if (r->count[v] > sizeof s->t / sizeof s->t[0])
        return false;
    s->v = v, s->start = r->start[v], s->room = r->room[v], s->count = r->count[v];
    memcpy(s->t, r->vt + r->start[v], r->count[v] * sizeof *s->t);
    return true;
}

/* Adds v to the ring unless there already; false when full. */
static bool add_ring(sp_snapshot *s, uint32_t v)
{
    for (int i = 0; i < s->nring; i++)
        if (s->ring[i] == v)
            return true;
    if (s->nring >= SP_TRIAL_MAX_RING)
        return false;
    s->ring[s->nring++] = v;
    return true;
}

bool sp_snapshot_take(const rm_pass *p, const rm_merge *g, sp_snapshot *s)
{
    const rm_mesh *r = &p->r;
    const ism_mesh *m = r->m;
    s->nring = s->ntri = 0;
    const uint32_t ends[2] = {g->v, g->w};
    for (int e = 0; e < 2; e++)
        for (uint32_t i = 0; i < r->count[ends[e]]; i++) {
            uint32_t t = r->vt[r->start[ends[e]] + i];
            int j = 0;
            while (j < s->ntri && s->tri[j] != t)
                j++;
            if (j == s->ntri) {
                if (s->ntri >= SP_TRIAL_MAX_TRIS)
                    return false;
                s->tri[s->ntri] = t;
                memcpy(s->corners[s->ntri++], m->tri + 3 * (size_t)t, 3 * sizeof(uint32_t));
            }
            for (int k = 0; k < 3; k++)
                if (!add_ring(s, m->tri[3 * (size_t)t + k]))
                    return false;
        }
    for (int i = 0; i < s->nring; i++) {
        uint32_t v = s->ring[i];
        memcpy(s->pos[i], m->pos + 3 * (size_t)v, sizeof s->pos[i]);
        memcpy(s->normal[i], p->normal + 3 * (size_t)v, sizeof s->normal[i]);
        memcpy(s->mesh_normal[i], m->normal + 3 * (size_t)v, sizeof s->mesh_normal[i]);
        s->active[i] = p->active[v];
    }
    const uint32_t slots[SP_TRIAL_SLOTS] = {g->v, g->w, g->c, g->d};
    for (int i = 0; i < SP_TRIAL_SLOTS; i++)
        if (!take_slot(r, slots[i], &s->slot[i]))
            return false;
    s->v = g->v;
    s->v_flags[0] = r->gone[g->v], s->v_flags[1] = r->locked[g->v];
    s->v_flags[2] = p->slide[g->v], s->v_flags[3] = p->active[g->v];
    s->collapses = p->collapses, s->moves = p->moves;
    return true;
}

void sp_snapshot_restore(rm_pass *p, const sp_snapshot *s)
{
    rm_mesh *r = &p->r;
    ism_mesh *m = r->m;
    for (int i = 0; i < s->nring; i++) {
        uint32_t v = s->ring[i];
        memcpy(m->pos + 3 * (size_t)v, s->pos[i], sizeof s->pos[i]);
        memcpy(p->normal + 3 * (size_t)v, s->normal[i], sizeof s->normal[i]);
        memcpy(m->normal + 3 * (size_t)v, s->mesh_normal[i], sizeof s->mesh_normal[i]);
        p->active[v] = s->active[i];
    }
    for (int j = 0; j < s->ntri; j++) {
        memcpy(m->tri + 3 * (size_t)s->tri[j], s->corners[j], sizeof s->corners[j]);
        r->dead[s->tri[j]] = 0;
    }
    /* a slot the merge grew moved to the end of vt; its old place still holds nothing else */
    for (int i = 0; i < SP_TRIAL_SLOTS; i++) {
        const sp_slot *sl = &s->slot[i];
        r->start[sl->v] = sl->start, r->room[sl->v] = sl->room, r->count[sl->v] = sl->count;
        memcpy(r->vt + sl->start, sl->t, sl->count * sizeof *sl->t);
    }
    r->gone[s->v] = s->v_flags[0], r->locked[s->v] = s->v_flags[1];
    p->slide[s->v] = s->v_flags[2], p->active[s->v] = s->v_flags[3];
    p->collapses = s->collapses, p->moves = s->moves;
}

/* Every centroid and edge midpoint of v's triangles, and v when free, within max_error (a
 * locked vertex is where the features put it). */
static bool fan_within(rm_pass *p, uint32_t v)
{
    const rm_mesh *r = &p->r;
    const double *P = r->m->pos;
    if (!r->locked[v] && !(rm_bound_distance(p, P + 3 * (size_t)v, p->max_error) <= p->max_error))
        return false;
    for (uint32_t i = 0; i < r->count[v]; i++) {
        const uint32_t *t = r->m->tri + 3 * r->vt[r->start[v] + i];
        const double *a = P + 3 * (size_t)t[0], *b = P + 3 * (size_t)t[1], *c = P + 3 * (size_t)t[2];
        if (!rm_bound_triangle(p, a, b, c) || !rm_bound_edge(p, a, b) ||
            !rm_bound_edge(p, b, c) || !rm_bound_edge(p, c, a))
            return false;
    }
    return true;
}

/* Marks in beyond[] (by ring index) the corners other than w of each triangle of w's fan
 * whose centroid lies beyond max_error, and the far end of each edge at w whose midpoint
 * does: the vertices whose moves can bring those points back. (The points were measured by
 * the verdict just before: the memo answers.) */
static void mark_beyond(rm_pass *p, const sp_snapshot *s, uint32_t w, bool *beyond)
{
    const rm_mesh *r = &p->r;
    const double *P = r->m->pos;
    uint32_t mark[3 * ISM_RM_MERGE_MAX_DEGREE];
    int n = 0;
    for (uint32_t i = 0; i < r->count[w]; i++) {
        const uint32_t *t = r->m->tri + 3 * r->vt[r->start[w] + i];
        bool centroid = !rm_bound_triangle(p, P + 3 * (size_t)t[0], P + 3 * (size_t)t[1],
                                           P + 3 * (size_t)t[2]);
        for (int k = 0; k < 3; k++) {
            uint32_t u = t[k], next = t[(k + 1) % 3];
            bool edge = (u == w || next == w) &&
                        !rm_bound_edge(p, P + 3 * (size_t)u, P + 3 * (size_t)next);
            if ((centroid || edge) && u != w && n < 3 * ISM_RM_MERGE_MAX_DEGREE)
                mark[n++] = u;
            if (edge && next != w && n < 3 * ISM_RM_MERGE_MAX_DEGREE)
                mark[n++] = next;
        }
    }
    for (int i = 0; i < s->nring; i++)
        for (int j = 0; j < n && !beyond[i]; j++)
            beyond[i] = s->ring[i] == mark[j];
}

bool sp_ring_settle(rm_pass *p, const sp_snapshot *s, uint32_t w)
{
    const rm_mesh *r = &p->r;
    bool moved[SP_TRIAL_MAX_RING] = {false}, beyond[SP_TRIAL_MAX_RING] = {false};
    mark_beyond(p, s, w, beyond);
    for (int i = 0; i < s->nring; i++) {
        uint32_t u = s->ring[i];
        if (u == w || !beyond[i] || r->locked[u] || r->gone[u] || !r->count[u])
            continue;
        moved[i] = rm_relax_vertex(p, u);
        moved[i] |= sp_offset_vertex(p, u);
    }
    if (!r->locked[w])
        sp_offset_vertex(p, w);
    for (int i = 0; i < s->nring; i++) {
        uint32_t u = s->ring[i];
        if ((u == w || moved[i]) && !fan_within(p, u))
            return false;
    }
    return true;
}
