/* remesh.c — the quality pass in order (remesh.h): ∇f normals, protection, then rounds of
 * Lawson flips (to a fixed point or the sweep limit) and one relaxation sweep, ending with
 * flips so the last moves' quads are Delaunay too. */
#include "core/remesh/remesh.h"
#include "core/remesh/rm_pass.h"
#include "core/util/clock.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Rounds of (flips, relaxation): the smallest angle rises fastest in the first few and is
 * flat after about eight on the presets (measured: sphere, torus, pretzel). */
#define ISM_RM_ROUNDS 8
/* Flip sweeps per round at most: each sweep flips every edge that fails the test once;
 * Lawson's procedure ends in a few sweeps on a mesh that is nearly Delaunay already. */
#define ISM_RM_FLIP_SWEEPS 6

double ism_remesh_min_angle(const ism_mesh *m)
{
    double worst = 90;
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *v = m->tri + 3 * t;
        const double *a = m->pos + 3 * v[0], *b = m->pos + 3 * v[1], *c = m->pos + 3 * v[2];
        double n[3], area = rm_cross(a, b, c, n);
        double l = fmax(rm_dist(a, b), fmax(rm_dist(b, c), rm_dist(c, a)));
        if (area > 1e-12 * l * l) /* the analysis's degenerate-triangle rule */
            worst = fmin(worst, rm_min_angle(a, b, c) * 180 / M_PI);
    }
    return worst;
}

static bool stopped(const ism_remesh_options *o) { return o->cancel && *o->cancel; }

static void flip_to_fixed_point(rm_pass *p, const ism_remesh_options *o)
{
    for (int s = 0; s < ISM_RM_FLIP_SWEEPS && !stopped(o); s++)
        if (!rm_flip_sweep(p))
            break;
}

bool ism_remesh_quality(ism_mesh *m, const ism_remesh_options *o, ism_remesh_stats *st,
                        ism_error *err)
{
    double t0 = ism_now_ms();
    memset(st, 0, sizeof *st);
    st->min_angle_before = ism_remesh_min_angle(m);
    if (!o->f)
        return ism_error_set(err, "quality pass: no function to project onto");
    rm_pass p;
    memset(&p, 0, sizeof p);
    p.f = o->f;
    p.max_error = o->max_error > 0 ? o->max_error : 0;
    p.r.label = o->tri_label;
    p.ws = ism_eval_ws_new(o->f);
    p.normal = malloc((m->nverts ? m->nverts : 1) * 3 * sizeof *p.normal);
    bool ok = p.ws && p.normal && rm_mesh_build(&p.r, m) && rm_normals(&p) &&
              rm_lock_features(&p, o);
    if (ok) {
        for (int round = 0; round < ISM_RM_ROUNDS && !stopped(o); round++) {
            flip_to_fixed_point(&p, o);
            if (!stopped(o))
                rm_relax_sweep(&p);
        }
        flip_to_fixed_point(&p, o);
        for (size_t v = 0; v < m->nverts; v++)
            st->locked_vertices += p.r.locked[v] && p.r.count[v];
    }
    st->flips = p.flips;
    st->moves = p.moves;
    st->min_angle_after = ism_remesh_min_angle(m);
    rm_mesh_free(&p.r);
    free(p.normal);
    ism_eval_ws_free(p.ws);
    st->time_ms = ism_now_ms() - t0;
    return ok ? true : ism_error_set(err, "quality pass: out of memory");
}
