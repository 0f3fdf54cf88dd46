/* crease_normals.c — per-corner normals from each triangle's branch of f: on a smooth part
 * they equal the vertex normals (∇f), across a crease the two sides' corners at a crease
 * vertex get their own branches' gradients. */
#include "core/curves/crease_normals.h"
#include <math.h>
#include <string.h>
#include "core/curves/branches.h"

/* The triangle's own normal (its winding is counter-clockwise seen from where ∇f points). */
static void face_normal(const ism_mesh *m, const uint32_t *tv, double n[3])
{
    const double *a = m->pos + 3 * (size_t)tv[0], *b = m->pos + 3 * (size_t)tv[1],
                 *c = m->pos + 3 * (size_t)tv[2];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = u[1] * w[2] - u[2] * w[1];
    n[1] = u[2] * w[0] - u[0] * w[2];
    n[2] = u[0] * w[1] - u[1] * w[0];
}

/* The branch's unit gradient at vertex v, on the side of ref (the vertex normal when no
 * branch: at a crease the other branch's normal may face away by more than 90°). */
static void corner(ism_branches *b, uint32_t br, const ism_mesh *m, uint32_t v,
                   const double ref[3], float *out)
{
    memcpy(out, m->normal + 3 * (size_t)v, 3 * sizeof *out);
    if (br == ISM_BRANCH_NONE)
        return;
    double g[3];
    ism_branches_gradient(b, br, m->pos + 3 * (size_t)v, g);
    double n = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    double d = g[0] * ref[0] + g[1] * ref[1] + g[2] * ref[2];
    if (!(n > 0) || !isfinite(n))
        return;
    double k = d < 0 ? -1 / n : 1 / n;
    for (int i = 0; i < 3; i++)
        out[i] = (float)(g[i] * k);
}

bool ism_crease_corner_normals(const ism_tape *f, const ism_mesh *m, float *out)
{
    ism_branches b;
    memset(&b, 0, sizeof b);
    bool any = ism_branches_any(f);
    if (any && !ism_branches_init(&b, f))
        return false;
    bool ok = true;
    for (size_t t = 0; ok && t < m->ntris; t++) {
        const uint32_t *tv = m->tri + 3 * t;
        uint32_t br = ISM_BRANCH_NONE;
        if (any) {
            double c[3] = {0, 0, 0};
            for (int i = 0; i < 3; i++)
                for (int k = 0; k < 3; k++)
                    c[k] += m->pos[3 * (size_t)tv[i] + k] / 3;
            ok = ism_branches_at(&b, c, &br);
        }
        double fn[3];
        face_normal(m, tv, fn);
        for (int i = 0; ok && i < 3; i++)
            corner(&b, br, m, tv[i], fn, out + 9 * t + 3 * i);
    }
    if (any)
        ism_branches_free(&b);
    return ok;
}
