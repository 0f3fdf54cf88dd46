/* corner_split.c — the vertex split of corner_split.h: for each corner, the point of its
 * vertex with its triangle's labels is looked up in the vertex's short list of points (a
 * vertex meets few cells) and made when missing. */
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
    memset(s, 0, sizeof *s);
}

/* The point of vertex v with labels (cell, sheet): found in v's list or appended. */
static uint32_t point_of(ism_corner_split *s, uint32_t *first, uint32_t *next, uint32_t v,
                         uint32_t cell, uint8_t sheet)
{
    for (uint32_t p = first[v]; p != NONE; p = next[p])
        if ((!s->point_cell || s->point_cell[p] == cell) &&
            (!s->point_sheet || s->point_sheet[p] == sheet))
            return p;
    uint32_t p = (uint32_t)s->npoints++;
    s->point_vertex[p] = v;
    if (s->point_cell)
        s->point_cell[p] = cell;
    if (s->point_sheet)
        s->point_sheet[p] = sheet;
    next[p] = first[v];
    first[v] = p;
    return p;
}

bool ism_corner_split_build(const uint32_t *tri, size_t ntris, size_t nverts,
                            const uint32_t *tri_cell, const uint8_t *tri_sheet,
                            ism_corner_split *out)
{
    memset(out, 0, sizeof *out);
    size_t corners = 3 * ntris;
    if ((!tri_cell && !tri_sheet) || corners >= NONE || nverts >= NONE)
        return false;
    size_t cap = corners ? corners : 1; /* at most one point per corner */
    out->tri = malloc(cap * sizeof *out->tri);
    out->point_vertex = malloc(cap * sizeof *out->point_vertex);
    out->point_cell = tri_cell ? malloc(cap * sizeof *out->point_cell) : NULL;
    out->point_sheet = tri_sheet ? malloc(cap) : NULL;
    uint32_t *first = malloc((nverts ? nverts : 1) * sizeof *first);
    uint32_t *next = malloc(cap * sizeof *next);
    bool ok = out->tri && out->point_vertex && (!tri_cell || out->point_cell) &&
              (!tri_sheet || out->point_sheet) && first && next;
    if (ok) {
        memset(first, 0xff, (nverts ? nverts : 1) * sizeof *first);
        for (size_t t = 0; t < ntris; t++)
            for (int k = 0; k < 3; k++)
                out->tri[3 * t + k] = point_of(out, first, next, tri[3 * t + k],
                                               tri_cell ? tri_cell[t] : 0,
                                               tri_sheet ? tri_sheet[t] : 0);
    }
    free(first);
    free(next);
    if (!ok)
        ism_corner_split_free(out);
    return ok;
}
