/* arrangement.c — building the arrangement (faces, then the curve graph) and its Euler check:
 * in every mesh component V − E + Σ χ°(face) of the arrangement must equal V − E + T of the
 * mesh, χ° counting each face's triangles with the edges and vertices inside it. */
#include "core/curves/arr_internal.h"
#include <stdlib.h>
#include <string.h>

void ism_arrangement_free(ism_arrangement *a)
{
    free(a->vertices);
    free(a->edges);
    free(a->faces);
    free(a->curves);
    free(a->chain);
    free(a->tri_face);
    memset(a, 0, sizeof *a);
}

/* The mesh component of arrangement edge i: its first mesh edge's (its end vertices may
 * be shared by components that touch at a point, as the nappes of a cone at its apex). */
static uint32_t edge_component(const ism_arrangement *a, const arr_mesh_edges *e,
                               const uint32_t *ecomp, const uint32_t *vcomp, size_t i)
{
    const ism_arr_edge *ae = &a->edges[i];
    uint32_t k = ae->count > 1 ? arr_edge_find(e, a->chain[ae->first], a->chain[ae->first + 1])
                               : ARR_NO_EDGE;
    return k != ARR_NO_EDGE ? ecomp[k] : vcomp[a->vertices[ae->from].v];
}

/* Per component: mesh χ into em, arrangement χ into ea; vcomp maps mesh vertices (a vertex
 * to the first component seen using it: the same one on both sides). False when out of
 * memory. */
static bool euler_check(const ism_mesh *m, const arr_mesh_edges *e, const uint32_t *comp,
                        ism_arrangement *a, long *em, long *ea, uint32_t *vcomp)
{
    uint32_t *ecomp = malloc((e->n + 1) * sizeof *ecomp); /* per mesh edge */
    if (!ecomp)
        return false;
    memset(ecomp, 0xff, (e->n + 1) * sizeof *ecomp);
    for (size_t t = 0; t < m->ntris; t++) {
        em[comp[t]]++;
        for (int i = 0; i < 3; i++) {
            uint32_t v = m->tri[3 * t + i], k = e->tri_edge[3 * t + i];
            if (vcomp[v] == UINT32_MAX) {
                vcomp[v] = comp[t];
                em[comp[t]]++;
            }
            if (ecomp[k] == UINT32_MAX) {
                ecomp[k] = comp[t];
                em[comp[t]]--;
            }
        }
    }
    for (size_t i = 0; i < a->nvertices; i++)
        ea[vcomp[a->vertices[i].v]]++;
    for (size_t i = 0; i < a->nedges; i++)
        ea[edge_component(a, e, ecomp, vcomp, i)]--;
    free(ecomp);
    for (size_t f = 0; f < a->nfaces; f++)
        ea[a->faces[f].component] += a->faces[f].euler_open;
    a->euler_mesh = a->euler_arr = 0;
    a->euler_ok = true;
    for (size_t k = 0; k < a->ncomponents; k++) {
        a->euler_mesh += em[k];
        a->euler_arr += ea[k];
        a->euler_ok &= em[k] == ea[k];
    }
    return true;
}

bool ism_arrangement_build(ism_mesh *m, ism_cut *c, const ism_locus *locus, double on_tol,
                           ism_arrangement *a)
{
    memset(a, 0, sizeof *a);
    arr_mesh_edges e;
    if (!arr_mesh_edges_build(m, c, &e))
        return false;
    uint32_t *comp = malloc((m->ntris + 1) * sizeof *comp);
    uint32_t *vcomp = malloc((m->nverts + 1) * sizeof *vcomp);
    uint32_t *sing = malloc((m->nverts + 1) * sizeof *sing);
    long *em = NULL, *ea = NULL;
    bool ok = comp && vcomp && sing && arr_singular_marks(m, c, &e, locus, on_tol, sing) &&
              arr_build_faces(m, &e, a, comp, c->tri_parent) && arr_build_graph(m, c, sing, a);
    if (ok) {
        em = calloc(a->ncomponents + 1, sizeof *em);
        ea = calloc(a->ncomponents + 1, sizeof *ea);
        ok = em && ea;
    }
    if (ok) {
        memset(vcomp, 0xff, (m->nverts + 1) * sizeof *vcomp);
        ok = euler_check(m, &e, comp, a, em, ea, vcomp);
    }
    free(comp);
    free(vcomp);
    free(sing);
    free(em);
    free(ea);
    arr_mesh_edges_free(&e);
    if (!ok)
        ism_arrangement_free(a);
    return ok;
}
