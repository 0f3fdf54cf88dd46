/* vertices.c — classifying vertices by their cones of faces (Pérez-Aquila & Aguilera 2003):
 * the triangles around a vertex fall into cones, the groups reached from one another by
 * crossing shared manifold edges. One cone is a manifold vertex, more than one is a
 * non-manifold point (a Kummer node, two sheets touching); a vertex on a boundary edge or a
 * non-manifold edge gets that class instead.
 *
 * Instead of walking each vertex's fan, every manifold edge joins the corners of its two
 * triangles at each of its two end points in one union-find over all corners; a vertex then
 * has (its corners) - (successful joins at it) cones. Linear in the mesh size. */
#include "core/analysis/vertices.h"
#include "core/analysis/unionfind.h"

#include <stdlib.h>
#include <string.h>

void ism_an_vertex_facts_free(ism_an_vertex_facts *vf)
{
    free(vf->corners);
    free(vf->cones);
    free(vf->nm_degree);
    free(vf->cone_sets);
    memset(vf, 0, sizeof *vf);
}

bool ism_an_count_corners(const ism_mesh *m, ism_an_vertex_facts *vf)
{
    memset(vf, 0, sizeof *vf);
    if (!(vf->corners = calloc(m->nverts ? m->nverts : 1, sizeof *vf->corners)))
        return false;
    for (size_t t = 0; t < m->ntris; t++)
        if (!ism_an_tri_collapsed(m->tri, t))
            for (int k = 0; k < 3; k++)
                vf->corners[m->tri[3 * t + k]]++;
    return true;
}

/* Joins, at both ends of the manifold edge with half-edges h1 and h2, the corners of its two
 * triangles; counts the joins that merged two cones. */
static void join_across(const uint32_t *tri, uint32_t *parent, uint32_t h1, uint32_t h2,
                        uint32_t *merges)
{
    uint32_t u = tri[h1], w = tri[ism_an_he_next(h1)];
    bool same_way = tri[h2] == u;
    uint32_t c2u = same_way ? h2 : ism_an_he_next(h2);
    uint32_t c2w = same_way ? ism_an_he_next(h2) : h2;
    if (ism_an_uf_union(parent, h1, c2u))
        merges[u]++;
    if (ism_an_uf_union(parent, ism_an_he_next(h1), c2w))
        merges[w]++;
}

/* Walks the edges once: marks boundary vertices, counts non-manifold edges per vertex and
 * joins corners across manifold edges. */
static bool scan_edges(const ism_mesh *m, const ism_an_edge_table *et, ism_an_vertex_facts *vf,
                       uint8_t *on_boundary, uint32_t *merges, ism_analysis *a)
{
    size_t nh = 3 * m->ntris;
    uint32_t *parent = vf->cone_sets = malloc((nh ? nh : 1) * sizeof *parent);
    if (!parent)
        return false;
    for (size_t h = 0; h < nh; h++)
        parent[h] = (uint32_t)h;
    for (uint32_t e = 0; e < et->nedges; e++) {
        uint32_t n = ism_an_edge_count(et, e), lo, hi;
        ism_an_edge_ends(m, et, e, &lo, &hi);
        if (n == 1) {
            a->boundary_edges++;
            on_boundary[lo] = on_boundary[hi] = 1;
        } else if (n == 2) {
            a->manifold_edges++;
            const uint32_t *he = et->edge_he + et->edge_start[e];
            join_across(m->tri, parent, he[0], he[1], merges);
        } else {
            a->nonmanifold_edges++;
            vf->nm_degree[lo]++;
            vf->nm_degree[hi]++;
        }
    }
    a->edges = et->nedges;
    return true;
}

static uint8_t vertex_class(const ism_an_vertex_facts *vf, const uint8_t *on_boundary, size_t v)
{
    if (vf->corners[v] == 0)
        return ISM_VERTEX_ISOLATED;
    if (vf->nm_degree[v] > 0)
        return ISM_VERTEX_NONMANIFOLD_EDGE;
    if (vf->cones[v] > 1)
        return ISM_VERTEX_NONMANIFOLD_POINT;
    if (on_boundary[v])
        return ISM_VERTEX_BOUNDARY;
    return ISM_VERTEX_MANIFOLD;
}

bool ism_an_classify_vertices(const ism_mesh *m, const ism_an_edge_table *et,
                              ism_an_vertex_facts *vf, ism_analysis *a)
{
    size_t nv = m->nverts, n = nv ? nv : 1;
    vf->cones = calloc(n, sizeof *vf->cones);
    vf->nm_degree = calloc(n, sizeof *vf->nm_degree);
    a->vertex_class = malloc(n);
    uint8_t *on_boundary = calloc(n, 1);
    uint32_t *merges = calloc(n, sizeof *merges);
    bool ok = vf->corners && vf->cones && vf->nm_degree && a->vertex_class && on_boundary &&
              merges;
    ok = ok && scan_edges(m, et, vf, on_boundary, merges, a);
    if (ok) {
        for (size_t v = 0; v < nv; v++) {
            vf->cones[v] = vf->corners[v] - merges[v];
            a->vertex_class[v] = vertex_class(vf, on_boundary, v);
            a->class_count[a->vertex_class[v]]++;
        }
        a->nonmanifold_vertices = a->class_count[ISM_VERTEX_NONMANIFOLD_EDGE] +
                                  a->class_count[ISM_VERTEX_NONMANIFOLD_POINT];
    }
    free(on_boundary);
    free(merges);
    return ok;
}
