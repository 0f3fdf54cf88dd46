/* boundary.c — boundary edges of a triangle mesh and their chains. Half-edges are bucketed by
 * their smaller vertex (counting sort, so O(triangles)); an undirected edge met exactly once
 * is a boundary edge, kept in the direction its triangle runs it. Boundary edges are then
 * linked head to tail: chains start where a vertex has more outgoing than incoming boundary
 * edges (a boundary that runs into a non-manifold vertex), and what remains closes in loops. */
#include "proto/features.h"

#include <stdlib.h>
#include <string.h>

void ism_polylines_free(ism_polylines *p)
{
    free(p->start);
    free(p->verts);
    memset(p, 0, sizeof *p);
}

typedef struct half {
    uint32_t other;   /* the larger vertex */
    uint32_t from;    /* start vertex of the directed edge */
    uint32_t to;
} half;

static int by_other(const void *a, const void *b)
{
    uint32_t x = ((const half *)a)->other, y = ((const half *)b)->other;
    return (x > y) - (x < y);
}

/* Directed boundary edges (from, to) into *edges; returns the count, or SIZE_MAX on OOM. */
static size_t boundary_edges(const ism_mesh *m, uint32_t **edges)
{
    size_t nv = m->nverts;
    uint32_t *first = calloc(nv + 1, sizeof *first);
    half *h = malloc((m->ntris ? m->ntris : 1) * 3 * sizeof *h);
    *edges = NULL;
    if (!first || !h) {
        free(first);
        free(h);
        return SIZE_MAX;
    }
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *v = m->tri + 3 * t;
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
            continue;
        for (int k = 0; k < 3; k++) {
            uint32_t a = v[k], b = v[(k + 1) % 3];
            first[(a < b ? a : b) + 1]++;
        }
    }
    for (size_t i = 0; i < nv; i++)
        first[i + 1] += first[i];
    size_t nh = first[nv];
    uint32_t *fill = malloc((nv ? nv : 1) * sizeof *fill);
    uint32_t *out = malloc((nh ? nh : 1) * 2 * sizeof *out);
    if (!fill || !out) {
        free(first);
        free(h);
        free(fill);
        free(out);
        return SIZE_MAX;
    }
    memcpy(fill, first, nv * sizeof *fill);
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *v = m->tri + 3 * t;
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
            continue;
        for (int k = 0; k < 3; k++) {
            uint32_t a = v[k], b = v[(k + 1) % 3];
            uint32_t lo = a < b ? a : b;
            h[fill[lo]++] = (half){a < b ? b : a, a, b};
        }
    }
    size_t nb = 0;
    for (size_t v = 0; v < nv; v++) {
        half *bucket = h + first[v];
        size_t n = first[v + 1] - first[v];
        if (n > 1)
            qsort(bucket, n, sizeof *bucket, by_other);
        for (size_t i = 0; i < n;) {
            size_t j = i + 1;
            while (j < n && bucket[j].other == bucket[i].other)
                j++;
            if (j - i == 1) {
                out[2 * nb] = bucket[i].from;
                out[2 * nb + 1] = bucket[i].to;
                nb++;
            }
            i = j;
        }
    }
    free(first);
    free(h);
    free(fill);
    *edges = out;
    return nb;
}

bool ism_boundary_chains(const ism_mesh *m, ism_polylines *out)
{
    memset(out, 0, sizeof *out);
    uint32_t *e;
    size_t ne = boundary_edges(m, &e);
    if (ne == SIZE_MAX)
        return false;
    size_t nv = m->nverts;
    /* Outgoing boundary edges per vertex (CSR), and in/out degrees. */
    uint32_t *ofirst = calloc(nv + 1, sizeof *ofirst);
    uint32_t *indeg = calloc(nv ? nv : 1, sizeof *indeg);
    uint32_t *oedge = malloc((ne ? ne : 1) * sizeof *oedge);
    uint32_t *cursor = malloc((nv ? nv : 1) * sizeof *cursor);
    out->start = malloc((ne + 1) * sizeof *out->start);
    out->verts = malloc((2 * ne + 1) * sizeof *out->verts);
    bool ok = ofirst && indeg && oedge && cursor && out->start && out->verts;
    if (ok) {
        for (size_t i = 0; i < ne; i++) {
            ofirst[e[2 * i] + 1]++;
            indeg[e[2 * i + 1]]++;
        }
        for (size_t v = 0; v < nv; v++)
            ofirst[v + 1] += ofirst[v];
        memcpy(cursor, ofirst, nv * sizeof *cursor);
        for (size_t i = 0; i < ne; i++)
            oedge[cursor[e[2 * i]]++] = (uint32_t)i;
        memcpy(cursor, ofirst, nv * sizeof *cursor);

        size_t nverts = 0;
        out->start[0] = 0;
        /* Pass 0 starts open chains at surplus vertices, pass 1 closes the loops. */
        for (int pass = 0; pass < 2; pass++) {
            for (size_t s = 0; s < nv; s++) {
                while (cursor[s] < ofirst[s + 1]) {
                    uint32_t outdeg_left = ofirst[s + 1] - cursor[s];
                    if (pass == 0 && outdeg_left <= indeg[s])
                        break;
                    /* Walk from s along unused edges. */
                    uint32_t v = (uint32_t)s;
                    out->verts[nverts++] = v;
                    while (cursor[v] < ofirst[v + 1]) {
                        uint32_t i = oedge[cursor[v]++];
                        v = e[2 * i + 1];
                        indeg[v]--;
                        out->verts[nverts++] = v;
                        if (pass == 1 && v == s)
                            break;
                    }
                    out->start[++out->n] = (uint32_t)nverts;
                }
            }
        }
    }
    free(e);
    free(ofirst);
    free(indeg);
    free(oedge);
    free(cursor);
    if (!ok)
        ism_polylines_free(out);
    return ok;
}
