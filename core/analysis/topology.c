/* topology.c — the global shape of the mesh: V - E + F, components (each with its own Euler
 * characteristic, boundary, orientability and genus), boundary loops, vertex components.
 * A vertex shared by two components (a Kummer node between two edge components) counts once
 * in each of them. */
#include "core/analysis/topology.h"
#include "core/analysis/boundary.h"
#include "core/analysis/components.h"
#include "core/analysis/orientation.h"
#include "core/analysis/unionfind.h"

#include <stdlib.h>
#include <string.h>

/* A corner of a vertex with several cones: which component and which cone it is in. */
typedef struct corner_place {
    uint32_t vertex, comp, cone;
} corner_place;

static int cmp_place(const void *x, const void *y)
{
    const corner_place *a = x, *b = y;
    if (a->vertex != b->vertex)
        return a->vertex < b->vertex ? -1 : 1;
    if (a->comp != b->comp)
        return a->comp < b->comp ? -1 : 1;
    return (a->cone > b->cone) - (a->cone < b->cone);
}

static void count_triangles_and_edges(const ism_mesh *m, const ism_an_edge_table *et,
                                      const uint32_t *comp, ism_analysis *a)
{
    for (size_t t = 0; t < m->ntris; t++)
        if (comp[t] != ISM_AN_NONE) {
            ism_component *c = &a->component[comp[t]];
            if (c->triangles++ == 0)
                c->first_triangle = (uint32_t)t;
        }
    for (uint32_t e = 0; e < et->nedges; e++) {
        ism_component *c = &a->component[comp[et->edge_he[et->edge_start[e]] / 3]];
        uint32_t n = ism_an_edge_count(et, e);
        c->edges++;
        c->boundary_edges += n == 1;
        c->nonmanifold_edges += n > 2;
    }
}

/* Vertices per component. A vertex with one cone of faces lies in one component: count it
 * at its first corner. The corners of the others (several cones, possibly in several
 * components) are sorted by (vertex, component, cone) and the vertex counts once per
 * component; a component holding two cones of one vertex is not a manifold (a component
 * that meets another only at a vertex may still be one). */
static bool count_vertices(const ism_mesh *m, ism_an_vertex_facts *vf, const uint32_t *comp,
                           ism_analysis *a)
{
    size_t nv = m->nverts, nplaces = 0;
    uint8_t *seen = calloc(nv ? nv : 1, 1);
    if (!seen)
        return false;
    for (size_t h = 0; h < 3 * m->ntris; h++) {
        uint32_t v = m->tri[h], c = comp[h / 3];
        if (c == ISM_AN_NONE)
            continue;
        if (vf->cones[v] > 1)
            nplaces++;
        else if (!seen[v]) {
            seen[v] = 1;
            a->component[c].vertices++;
        }
    }
    free(seen);
    corner_place *place = malloc((nplaces ? nplaces : 1) * sizeof *place);
    if (!place)
        return false;
    size_t k = 0;
    for (uint32_t h = 0; h < 3 * m->ntris; h++) {
        uint32_t v = m->tri[h], c = comp[h / 3];
        if (c != ISM_AN_NONE && vf->cones[v] > 1)
            place[k++] = (corner_place){v, c, ism_an_uf_find(vf->cone_sets, h)};
    }
    qsort(place, nplaces, sizeof *place, cmp_place);
    for (size_t i = 0; i < nplaces; i++) {
        bool same_vertex_comp = i > 0 && place[i].vertex == place[i - 1].vertex &&
                                place[i].comp == place[i - 1].comp;
        if (!same_vertex_comp)
            a->component[place[i].comp].vertices++;
        else if (place[i].cone != place[i - 1].cone)
            a->component[place[i].comp].manifold = false;
    }
    free(place);
    return true;
}

/* Genus of an orientable manifold component whose boundary chains all close into loops:
 * euler = 2 - 2 genus - loops. */
static long component_genus(const ism_component *c)
{
    if (!c->manifold || !c->orientable || c->boundary_chains > 0)
        return -1;
    long twice = 2 - c->euler - (long)c->boundary_loops;
    return twice >= 0 && twice % 2 == 0 ? twice / 2 : -1;
}

static void summarise(const ism_mesh *m, const ism_an_vertex_facts *vf, const uint8_t *bad,
                      ism_analysis *a)
{
    for (size_t v = 0; v < m->nverts; v++)
        a->vertices_used += vf->corners[v] > 0;
    a->triangles_used = m->ntris - a->collapsed_triangles;
    a->euler = (long)a->vertices_used - (long)a->edges + (long)a->triangles_used;
    a->orientable = true;
    for (size_t i = 0; i < a->components; i++) {
        ism_component *c = &a->component[i];
        c->euler = (long)c->vertices - (long)c->edges + (long)c->triangles;
        c->closed = c->boundary_edges == 0;
        c->manifold = c->manifold && c->nonmanifold_edges == 0;
        c->orientable = !bad[i];
        c->genus = component_genus(c);
        a->orientable = a->orientable && c->orientable;
    }
    a->genus = a->components == 1 && a->component[0].closed ? a->component[0].genus : -1;
}

bool ism_an_topology(const ism_mesh *m, const ism_an_edge_table *et, ism_an_vertex_facts *vf,
                     ism_analysis *a)
{
    size_t nt = m->ntris ? m->ntris : 1;
    uint32_t *comp = malloc(nt * sizeof *comp);
    uint8_t *bad = NULL;
    bool ok = comp && ism_an_edge_components(m, et, comp, &a->components);
    if (ok) {
        size_t nc = a->components ? a->components : 1;
        a->component = calloc(nc, sizeof *a->component);
        bad = calloc(nc, 1);
        ok = a->component && bad;
    }
    for (size_t i = 0; ok && i < a->components; i++)
        a->component[i].manifold = true;
    ok = ok && ism_an_orientation(m, et, comp, bad, &a->inconsistent_edges);
    if (ok) {
        count_triangles_and_edges(m, et, comp, a);
        ok = count_vertices(m, vf, comp, a) && ism_an_boundary_chains(m, et, vf, comp, a) &&
             ism_an_vertex_components(m, vf, &a->vertex_components);
    }
    if (ok)
        summarise(m, vf, bad, a);
    free(comp);
    free(bad);
    return ok;
}
