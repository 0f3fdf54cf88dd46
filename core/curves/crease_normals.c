/* crease_normals.c — per-corner normals from each triangle's branch of f: on a smooth part
 * they equal the vertex normals (∇f), across a crease the two sides' corners at a crease
 * vertex get their own branches' gradients. A triangle's branch is read at a corner off the
 * crease (the cut's crease edges say which are on it), the centroid only when none is.
 *
 * Orientation: branch i equals f where it is taken, so ∇f_i points the way ∇f does on its
 * side, which is how the mesh's normals point. Neither the vertex's normal (at a crease
 * vertex it is the other side's, possibly more than 90° away) nor the triangle's winding (a
 * sliver folded over near a crease) is a guide to the sign, so none is applied. */
#include "core/curves/crease_normals.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/curves/branches.h"
#include "core/util/vec3.h"

/* The branch's unit gradient at vertex v (as ∇f_i points); the vertex's own normal when no
 * branch, or where the branch's gradient vanishes (a double sheet's). */
static void corner(ism_branches *b, uint32_t br, const ism_mesh *m, uint32_t v, float *out)
{
    memcpy(out, m->normal + 3 * (size_t)v, 3 * sizeof *out);
    if (br == ISM_BRANCH_NONE)
        return;
    double g[3];
    ism_branches_gradient(b, br, m->pos + 3 * (size_t)v, g);
    double n = sqrt(ism_dot3(g, g));
    if (!(n > 0) || !isfinite(n))
        return;
    for (int i = 0; i < 3; i++)
        out[i] = (float)(g[i] / n);
}

/* The branch triangle tv lies on: f's at its first corner not on the crease (on[v] 0),
 * else at its centroid. */
static bool triangle_branch(ism_branches *b, const ism_mesh *m, const uint8_t *on,
                            const uint32_t *tv, uint32_t *br)
{
    *br = ISM_BRANCH_NONE;
    for (int i = 0; on && i < 3 && *br == ISM_BRANCH_NONE; i++)
        if (!on[tv[i]] && !ism_branches_at(b, m->pos + 3 * (size_t)tv[i], br))
            return false;
    if (*br != ISM_BRANCH_NONE)
        return true;
    double c[3] = {0, 0, 0};
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            c[k] += m->pos[3 * (size_t)tv[i] + k] / 3;
    return ism_branches_at(b, c, br);
}

/* Per vertex of m: 1 at an end of a crease edge of cut (NULL when cut is NULL or out of
 * memory: *ok says which). */
static uint8_t *crease_vertices(const ism_mesh *m, const ism_cut *cut, bool *ok)
{
    *ok = true;
    if (!cut)
        return NULL;
    uint8_t *on = calloc(m->nverts + 1, 1);
    *ok = on != NULL;
    for (size_t i = 0; on && i < cut->nedges; i++)
        if (cut->edges[i].branch[0] != ISM_CUT_NO_BRANCH)
            on[cut->edges[i].a] = on[cut->edges[i].b] = 1;
    return on;
}

bool ism_crease_corner_normals(const ism_tape *f, const ism_mesh *m, const ism_cut *cut,
                               float *out)
{
    if (!ism_branches_any(f)) {
        for (size_t t = 0; t < m->ntris; t++)
            for (int i = 0; i < 3; i++)
                memcpy(out + 9 * t + 3 * i, m->normal + 3 * (size_t)m->tri[3 * t + i],
                       3 * sizeof *out);
        return true;
    }
    ism_branches b;
    memset(&b, 0, sizeof b);
    bool ok;
    uint8_t *on = crease_vertices(m, cut, &ok);
    if (!ok || !ism_branches_init(&b, f)) {
        free(on);
        return false;
    }
    for (size_t t = 0; ok && t < m->ntris; t++) {
        const uint32_t *tv = m->tri + 3 * t;
        uint32_t br;
        ok = triangle_branch(&b, m, on, tv, &br);
        for (int i = 0; ok && i < 3; i++)
            corner(&b, br, m, tv[i], out + 9 * t + 3 * i);
    }
    ism_branches_free(&b);
    free(on);
    return ok;
}
