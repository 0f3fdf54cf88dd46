/* crease_snap.c — vertices next to the crease moved onto it (crease_snap.h). A vertex of
 * branch A with neighbours of one other branch B goes to the crease point f_A = f_B = 0 that
 * Newton finds from it (minimum-norm steps: the nearest) when that is within
 * CREASE_SNAP_FRACTION of its shortest edge and each triangle of its star keeps its
 * orientation. The crossing estimated linearly along the edges is no guide: f_A − f_B of the
 * gyroid ball bends so that a vertex 6e-5 from the crease estimated its crossing at 0.39 of
 * an edge, and the polygoniser's vertices lie off f = 0 by up to 1e-5, so Newton's point can
 * be twice as far as the crossing on the edge. Asking also that the star get no thinner kept
 * more slivers than it saved (266 gyroid-ball crease edges over 2° instead of 236). */
#include "core/curves/crease_snap.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/util/vec3.h"

/* A crease point this close to a vertex (a fraction of its shortest edge) would leave
 * slivers about that thin when the cut splits its edges: the vertex moves there. */
#define CREASE_SNAP_FRACTION 0.2
/* A star triangle's new normal must keep this cosine with its old one (no triangle turned
 * over or folded up against its neighbours: 60°). */
#define CREASE_SNAP_TURN_COS 0.5
/* Star sizes handled (a polygoniser vertex has 3–12 triangles round it). */
#define CREASE_SNAP_STAR_MAX 32

typedef struct snap_star {
    uint32_t tri[CREASE_SNAP_STAR_MAX];
    size_t n;
} snap_star;

/* Whether every edge from v is in exactly two of the star's triangles (a closed fan: not at
 * the box, not on a non-manifold edge). */
static bool closed_fan(const ism_mesh *m, const snap_star *st, uint32_t v)
{
    for (size_t i = 0; i < st->n; i++)
        for (int c = 0; c < 3; c++) {
            uint32_t w = m->tri[3 * (size_t)st->tri[i] + c];
            if (w == v)
                continue;
            int seen = 0;
            for (size_t j = 0; j < st->n; j++) {
                const uint32_t *u = m->tri + 3 * (size_t)st->tri[j];
                seen += u[0] == w || u[1] == w || u[2] == w;
            }
            if (seen != 2)
                return false;
        }
    return true;
}

/* The one other branch among v's neighbours (*B; ISM_BRANCH_NONE when none, or when they
 * take two others or a tie: a junction, left to the cut) and v's shortest edge (*h). */
static void other_branch(const ism_mesh *m, const uint32_t *label, const snap_star *st,
                         uint32_t v, uint32_t *B, double *h)
{
    *B = ISM_BRANCH_NONE;
    *h = INFINITY;
    bool junction = false;
    for (size_t i = 0; i < st->n; i++)
        for (int c = 0; c < 3; c++) {
            uint32_t w = m->tri[3 * (size_t)st->tri[i] + c];
            if (w == v)
                continue;
            *h = fmin(*h, ism_sqdist3(m->pos + 3 * (size_t)v, m->pos + 3 * (size_t)w));
            if (label[w] == label[v])
                continue;
            junction |= label[w] == ISM_BRANCH_NONE || (*B != ISM_BRANCH_NONE && label[w] != *B);
            *B = label[w];
        }
    *h = sqrt(*h);
    if (junction)
        *B = ISM_BRANCH_NONE;
}

/* Moves v onto the crease between its branch and B when the crease point is within reach
 * and its star keeps its orientation. */
static bool try_snap(cut_state *s, ism_branches *b, uint32_t *label, const snap_star *st,
                     uint32_t v, uint32_t B, double reach)
{
    ism_mesh *m = s->m;
    double p[3];
    memcpy(p, m->pos + 3 * (size_t)v, sizeof p);
    size_t ks[1] = {B};
    if (!ism_branches_refine(b, label[v], ks, 1, NULL, s->tol, reach, p))
        return false;
    for (size_t i = 0; i < st->n; i++) {
        const uint32_t *tv = m->tri + 3 * (size_t)st->tri[i];
        double n0[3], n1[3];
        cut_tri_normal(m, tv, v, m->pos + 3 * (size_t)v, n0);
        cut_tri_normal(m, tv, v, p, n1);
        ism_normalise3(n0);
        ism_normalise3(n1);
        if (!(ism_dot3(n0, n1) >= CREASE_SNAP_TURN_COS))
            return false;
    }
    memcpy(m->pos + 3 * (size_t)v, p, sizeof p);
    cut_normal_at(s, p, NULL, m->normal + 3 * (size_t)v);
    label[v] = ISM_BRANCH_NONE;
    return true;
}

bool cut_crease_snap(cut_state *s, ism_branches *b, uint32_t *label, size_t *moved)
{
    ism_mesh *m = s->m;
    size_t nv = m->nverts, nt = m->ntris;
    uint32_t *first = calloc(nv + 2, sizeof *first), *star = malloc((3 * nt + 1) * sizeof *star);
    *moved = 0;
    if (!first || !star) {
        free(first);
        free(star);
        return false;
    }
    for (size_t i = 0; i < 3 * nt; i++) /* the triangles round each vertex, as a CSR */
        first[m->tri[i] + 2]++;
    for (size_t v = 0; v < nv; v++)
        first[v + 2] += first[v + 1];
    for (size_t i = 0; i < 3 * nt; i++)
        star[first[m->tri[i] + 1]++] = (uint32_t)(i / 3);
    for (size_t v = 0; v < nv; v++) {
        snap_star st = {.n = first[v + 1] - first[v]};
        if (label[v] == ISM_BRANCH_NONE || st.n < 3 || st.n > CREASE_SNAP_STAR_MAX)
            continue;
        memcpy(st.tri, star + first[v], st.n * sizeof *st.tri);
        uint32_t B;
        double h;
        other_branch(m, label, &st, (uint32_t)v, &B, &h);
        if (B != ISM_BRANCH_NONE && closed_fan(m, &st, (uint32_t)v))
            *moved += try_snap(s, b, label, &st, (uint32_t)v, B, CREASE_SNAP_FRACTION * h);
    }
    free(first);
    free(star);
    return true;
}
