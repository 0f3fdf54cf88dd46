/* arr_faces.c — the arrangement's faces: triangles joined across every mesh edge that lies on
 * no curve are one face; faces are numbered by their first triangle and the mesh's triangles
 * reordered so each face is one range; per face its area, closed and open Euler
 * characteristics and the number of boundary cycles. A vertex off the curves that faces
 * share without an edge — a node where two cones of the mesh meet, each cone a face of its
 * own — is one vertex of the mesh: the open characteristics count it once, in the first of
 * its faces (the one whose mesh component the Euler check gives it), so that they sum to
 * the mesh's χ. */
#include "core/curves/arr_internal.h"
#include "core/util/vec3.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NONE UINT32_MAX

/* Dense ids 0.. for the roots of parent, in order of each set's smallest member. */
static size_t number_sets(uint32_t *parent, size_t n, uint32_t *id)
{
    size_t k = 0;
    for (size_t i = 0; i < n; i++)
        id[i] = ism_an_uf_find(parent, (uint32_t)i) == i ? (uint32_t)k++ : NONE;
    for (size_t i = 0; i < n; i++)
        id[i] = id[ism_an_uf_find(parent, (uint32_t)i)];
    return k;
}

/* Cell and component union-finds over the triangles. */
static bool join_triangles(const ism_mesh *m, const arr_mesh_edges *e, uint32_t *cell,
                           uint32_t *comp)
{
    uint32_t *first = malloc((e->n + 1) * sizeof *first);
    if (!first)
        return false;
    memset(first, 0xff, (e->n + 1) * sizeof *first);
    for (size_t t = 0; t < m->ntris; t++)
        cell[t] = comp[t] = (uint32_t)t;
    for (size_t t = 0; t < m->ntris; t++)
        for (int i = 0; i < 3; i++) {
            uint32_t k = e->tri_edge[3 * t + i];
            if (first[k] == NONE) {
                first[k] = (uint32_t)t;
                continue;
            }
            (void)ism_an_uf_union(comp, first[k], (uint32_t)t);
            if (!e->on_curve[k])
                (void)ism_an_uf_union(cell, first[k], (uint32_t)t);
        }
    free(first);
    return true;
}

/* Moves triangle data (and parent, when not NULL) into face order (stable counting sort by
 * face id). */
static bool reorder(ism_mesh *m, arr_mesh_edges *e, const uint32_t *fid, size_t nf,
                    uint32_t *comp, uint32_t *parent, ism_arrangement *a)
{
    size_t nt = m->ntris;
    size_t *start = calloc(nf + 1, sizeof *start);
    uint32_t *tri = malloc((3 * nt + 1) * sizeof *tri), *te = malloc((3 * nt + 1) * sizeof *te);
    uint32_t *cp = malloc((nt + 1) * sizeof *cp), *pp = malloc((nt + 1) * sizeof *pp);
    bool ok = start && tri && te && cp && pp;
    if (ok) {
        for (size_t t = 0; t < nt; t++)
            start[fid[t] + 1]++;
        for (size_t f = 0; f < nf; f++)
            start[f + 1] += start[f];
        for (size_t f = 0; f < nf; f++) {
            a->faces[f].first = start[f];
            a->faces[f].ntris = start[f + 1] - start[f];
        }
        for (size_t t = 0; t < nt; t++) {
            size_t d = start[fid[t]]++;
            memcpy(tri + 3 * d, m->tri + 3 * t, 3 * sizeof *tri);
            memcpy(te + 3 * d, e->tri_edge + 3 * t, 3 * sizeof *te);
            cp[d] = comp[t];
            pp[d] = parent ? parent[t] : 0;
            a->tri_face[d] = fid[t];
        }
        memcpy(m->tri, tri, 3 * nt * sizeof *tri);
        memcpy(e->tri_edge, te, 3 * nt * sizeof *te);
        memcpy(comp, cp, nt * sizeof *cp);
        if (parent)
            memcpy(parent, pp, nt * sizeof *pp);
    }
    free(start);
    free(tri);
    free(te);
    free(cp);
    free(pp);
    return ok;
}

typedef struct face_scratch {
    uint32_t *vstamp, *estamp, *rstamp, *vpar, *touched;
    uint8_t *vcounted; /* per vertex: an earlier face's open characteristic counted it */
} face_scratch;

/* Area, Euler characteristics and boundary cycles of face f. */
static void measure_face(const ism_mesh *m, const arr_mesh_edges *e, face_scratch *s,
                         uint32_t f, ism_arr_face *face)
{
    long V = 0, E = 0, Vin = 0, Ein = 0;
    size_t ntouched = 0;
    face->area = 0;
    for (size_t t = face->first; t < face->first + face->ntris; t++) {
        const uint32_t *tv = m->tri + 3 * t;
        face->area += ism_tri_area3(m->pos + 3 * (size_t)tv[0], m->pos + 3 * (size_t)tv[1],
                                    m->pos + 3 * (size_t)tv[2]);
        for (int i = 0; i < 3; i++) {
            uint32_t v = tv[i], k = e->tri_edge[3 * t + i];
            if (s->vstamp[v] != f + 1) {
                s->vstamp[v] = f + 1;
                V++;
                if (!e->v_on_curve[v] && !s->vcounted[v]) {
                    s->vcounted[v] = 1;
                    Vin++;
                }
            }
            if (s->estamp[k] == f + 1)
                continue;
            s->estamp[k] = f + 1;
            E++;
            Ein += !e->on_curve[k];
            if (e->on_curve[k] || e->ntri[k] == 1) {
                uint32_t b = tv[(i + 1) % 3];
                s->touched[ntouched++] = v;
                s->touched[ntouched++] = b;
                (void)ism_an_uf_union(s->vpar, v, b);
            }
        }
    }
    face->euler = V - E + (long)face->ntris;
    face->euler_open = Vin - Ein + (long)face->ntris;
    face->boundary = 0;
    for (size_t i = 0; i < ntouched; i++) { /* one count per root */
        uint32_t r = ism_an_uf_find(s->vpar, s->touched[i]);
        if (s->rstamp[r] != f + 1) {
            s->rstamp[r] = f + 1;
            face->boundary++;
        }
    }
    for (size_t i = 0; i < ntouched; i++)
        s->vpar[s->touched[i]] = s->touched[i];
}

static bool measure_faces(const ism_mesh *m, const arr_mesh_edges *e, ism_arrangement *a)
{
    face_scratch s = {
        .vstamp = calloc(m->nverts + 1, sizeof(uint32_t)),
        .estamp = calloc(e->n + 1, sizeof(uint32_t)),
        .rstamp = calloc(m->nverts + 1, sizeof(uint32_t)),
        .vpar = malloc((m->nverts + 1) * sizeof(uint32_t)),
        .touched = malloc((6 * m->ntris + 1) * sizeof(uint32_t)),
        .vcounted = calloc(m->nverts + 1, 1),
    };
    bool ok = s.vstamp && s.estamp && s.rstamp && s.vpar && s.touched && s.vcounted;
    if (ok) {
        for (size_t v = 0; v < m->nverts; v++)
            s.vpar[v] = (uint32_t)v;
        for (size_t f = 0; f < a->nfaces; f++)
            measure_face(m, e, &s, (uint32_t)f, &a->faces[f]);
    }
    free(s.vstamp);
    free(s.estamp);
    free(s.rstamp);
    free(s.vpar);
    free(s.touched);
    free(s.vcounted);
    return ok;
}

bool arr_build_faces(ism_mesh *m, arr_mesh_edges *e, ism_arrangement *a, uint32_t *comp,
                     uint32_t *tri_parent)
{
    size_t nt = m->ntris;
    uint32_t *cell = malloc((nt + 1) * sizeof *cell), *fid = malloc((nt + 1) * sizeof *fid);
    uint32_t *cid = malloc((nt + 1) * sizeof *cid);
    a->tri_face = malloc((nt + 1) * sizeof *a->tri_face);
    bool ok = cell && fid && cid && a->tri_face && join_triangles(m, e, cell, comp);
    if (ok) {
        a->nfaces = number_sets(cell, nt, fid);
        a->ncomponents = number_sets(comp, nt, cid);
        memcpy(comp, cid, nt * sizeof *comp);
        a->faces = calloc(a->nfaces + 1, sizeof *a->faces);
        ok = a->faces && reorder(m, e, fid, a->nfaces, comp, tri_parent, a) && measure_faces(m, e, a);
    }
    if (ok)
        for (size_t f = 0; f < a->nfaces; f++)
            a->faces[f].component = comp[a->faces[f].first];
    free(cell);
    free(fid);
    free(cid);
    return ok;
}
