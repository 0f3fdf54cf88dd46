/* simplify.c — the simplification in order (simplify.h): ∇f normals and protection, then
 * rounds of collapses (sp_collapse.c), each followed by Lawson flips and one relaxation sweep
 * under the measured bound (rm_flip.c, rm_relax.c with bounded set), until a round merges
 * little; a last round of flips, then the renumbering. */
#include "core/remesh/simplify.h"
#include "core/remesh/rm_pass.h"
#include "core/remesh/sp_collapse.h"
#include "core/util/clock.h"

#include <math.h>
#include <string.h>

/* Rounds of (collapses, flips, relaxation) at most: each vertex takes part in at most one
 * collapse a round, so a round removes at most half the vertices, and the polygoniser's
 * meshes under a bound are rarely more than 2^4 times too fine. */
#define ISM_SP_ROUNDS 10
/* A round that removes fewer than this share of the vertices ends the loop: the mesh is at
 * its bound nearly everywhere. */
#define ISM_SP_MIN_GAIN 0.01

static bool stopped(const ism_remesh_options *o) { return o->cancel && *o->cancel; }

/* Flips and one relaxation sweep over every vertex, under the bound. */
static void even_out(rm_pass *p, bool *ok)
{
    memset(p->active, 1, p->r.m->nverts);
    rm_flip_active(p, ok);
    if (*ok)
        rm_relax_sweep(p);
}

static size_t live_vertices(const rm_pass *p)
{
    size_t n = 0;
    for (size_t v = 0; v < p->r.m->nverts; v++)
        n += p->r.count[v] != 0;
    return n;
}

bool ism_remesh_simplify(ism_mesh *m, const ism_remesh_options *o, ism_simplify_stats *st,
                         ism_remesh_renumber *ren, ism_error *err)
{
    double t0 = ism_now_ms();
    memset(st, 0, sizeof *st);
    if (ren)
        memset(ren, 0, sizeof *ren);
    st->min_angle_before = ism_remesh_min_angle(m);
    st->triangles_before = m->ntris;
    if (!o->f)
        return ism_error_set(err, "simplification: no function to project onto");
    if (!(o->max_error > 0))
        return ism_error_set(err, "simplification: needs max_error above 0");
    rm_pass p;
    size_t nv = m->nverts, nt = m->ntris;
    bool ok = rm_pass_open(&p, m, o, 0);
    p.bounded = true;
    for (int round = 0; ok && round < ISM_SP_ROUNDS && !stopped(o); round++) {
        size_t live = live_vertices(&p);
        size_t made = sp_collapse_round(&p, o->cancel, &ok);
        st->rounds++;
        if (ok && !stopped(o))
            even_out(&p, &ok);
        if ((double)made < ISM_SP_MIN_GAIN * (double)live)
            break;
    }
    if (ok && !stopped(o)) {
        memset(p.active, 1, m->nverts);
        rm_flip_active(&p, &ok);
    }
    for (size_t v = 0; ok && v < m->nverts; v++)
        st->locked_vertices += p.r.locked[v] && p.r.count[v];
    st->collapses = p.collapses;
    st->flips = p.flips;
    st->moves = p.moves;
    st->stopped = stopped(o);
    if (!rm_pass_close(&p, nv, nt, ren))
        ok = false;
    st->triangles_after = m->ntris;
    st->min_angle_after = ism_remesh_min_angle(m);
    st->time_ms = ism_now_ms() - t0;
    return ok ? true : ism_error_set(err, "simplification: out of memory");
}
