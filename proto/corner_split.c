/* corner_split.c — the vertex split of corner_split.h: for each corner, the point of its
 * vertex with its triangle's labels and its corner's normal is looked up in the vertex's
 * short list of points (a vertex meets few cells and crease sides) and made when missing. */
#include "proto/corner_split.h"

#include <stdlib.h>
#include <string.h>

#define NONE UINT32_MAX

void ism_corner_split_free(ism_corner_split *s)
{
    free(s->tri);
    free(s->point_vertex);
    free(s->point_cell);
    free(s->point_sheet);
    free(s->point_normal);
    memset(s, 0, sizeof *s);
}

bool ism_corner_split_needed(const ism_wire_mesh *w)
{
    return w->tri_cell || w->tri_sheet || (w->normal && w->ncorner_normals);
}

/* What one corner's point must carry. */
typedef struct corner_key {
    uint32_t vertex, cell;
    uint8_t sheet;
    const float *normal;
} corner_key;

static bool point_is(const ism_corner_split *s, uint32_t p, const corner_key *k)
{
    return (!s->point_cell || s->point_cell[p] == k->cell) &&
           (!s->point_sheet || s->point_sheet[p] == k->sheet) &&
           (!s->point_normal || !memcmp(s->point_normal + 3 * (size_t)p, k->normal,
                                        3 * sizeof *k->normal));
}

/* The point of k's vertex with k's labels: found in the vertex's list or appended. */
static uint32_t point_of(ism_corner_split *s, uint32_t *first, uint32_t *next,
                         const corner_key *k)
{
    for (uint32_t p = first[k->vertex]; p != NONE; p = next[p])
        if (point_is(s, p, k))
            return p;
    uint32_t p = (uint32_t)s->npoints++;
    s->point_vertex[p] = k->vertex;
    if (s->point_cell)
        s->point_cell[p] = k->cell;
    if (s->point_sheet)
        s->point_sheet[p] = k->sheet;
    if (s->point_normal)
        memcpy(s->point_normal + 3 * (size_t)p, k->normal, 3 * sizeof *k->normal);
    next[p] = first[k->vertex];
    first[k->vertex] = p;
    return p;
}

static bool alloc_points(const ism_wire_mesh *w, bool normals, size_t cap,
                         ism_corner_split *out)
{
    out->tri = malloc(cap * sizeof *out->tri);
    out->point_vertex = malloc(cap * sizeof *out->point_vertex);
    out->point_cell = w->tri_cell ? malloc(cap * sizeof *out->point_cell) : NULL;
    out->point_sheet = w->tri_sheet ? malloc(cap) : NULL;
    out->point_normal = normals ? malloc(cap * 3 * sizeof *out->point_normal) : NULL;
    return out->tri && out->point_vertex && (!w->tri_cell || out->point_cell) &&
           (!w->tri_sheet || out->point_sheet) && (!normals || out->point_normal);
}

bool ism_corner_split_build(const ism_wire_mesh *w, ism_corner_split *out)
{
    memset(out, 0, sizeof *out);
    size_t corners = 3 * w->ntris;
    bool normals = w->normal && w->ncorner_normals;
    if (!ism_corner_split_needed(w) || corners >= NONE || w->nverts >= NONE)
        return false;
    size_t cap = corners ? corners : 1; /* at most one point per corner */
    uint32_t *first = malloc((w->nverts ? w->nverts : 1) * sizeof *first);
    uint32_t *next = malloc(cap * sizeof *next);
    bool ok = alloc_points(w, normals, cap, out) && first && next;
    if (ok) {
        memset(first, 0xff, (w->nverts ? w->nverts : 1) * sizeof *first);
        size_t j = 0; /* the next corner normal (ascending corners) */
        for (size_t c = 0; c < corners; c++) {
            corner_key k = {w->tri[c], w->tri_cell ? w->tri_cell[c / 3] : 0,
                            w->tri_sheet ? w->tri_sheet[c / 3] : 0, NULL};
            if (normals) {
                bool own = j < w->ncorner_normals && w->corner_at[j] == c;
                k.normal = own ? w->corner_normal + 3 * j++ : w->normal + 3 * (size_t)k.vertex;
            }
            out->tri[c] = point_of(out, first, next, &k);
        }
    }
    free(first);
    free(next);
    if (!ok)
        ism_corner_split_free(out);
    return ok;
}
