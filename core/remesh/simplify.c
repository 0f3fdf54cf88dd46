/* simplify.c — the simplification in order (simplify.h): ∇f normals and protection, then
 * rounds of collapses (sp_collapse.c), each followed by Lawson flips and one relaxation sweep
 * under the measured bound (rm_flip.c, rm_relax.c with bounded set), until a round merges
 * little; a last round of flips, then the renumbering. The pass's measures are remembered by
 * point (rm_memo.h): a centroid or midpoint measured by a verdict, a trial or a move is not
 * measured again while it stays where it is. */
#include "core/remesh/simplify.h"
#include "core/remesh/rm_memo.h"
#include "core/remesh/rm_pass.h"
#include "core/remesh/sp_collapse.h"
#include "core/util/clock.h"

#include <math.h>
#include <string.h>

/* Rounds of (collapses, flips, relaxation, offsets) at most: a merged vertex takes part in no
 * other collapse that round, so a round removes at most half the vertices; the presets'
 * meshes under a bound settle in 4 to 6 rounds. */
#define ISM_SP_ROUNDS 16
/* A round that removes fewer than this share of the vertices ends the loop: the mesh is at
 * its bound nearly everywhere, and a round after costs as much as the last for a few merges
 * (sphere at E = 7.9e-4: rounds merge 3312, 2308, 791, 122, 23 vertices). */
#define ISM_SP_MIN_GAIN 0.05

static bool stopped(const ism_remesh_options *o) { return o->cancel && *o->cancel; }

/* Adds the neighbours of the active vertices to them. */
static void grow_active(rm_pass *p)
{
    const rm_mesh *r = &p->r;
    for (size_t v = 0; v < r->m->nverts; v++)
        for (uint32_t i = 0; p->active[v] == 1 && i < r->count[v]; i++) {
            const uint32_t *t = r->m->tri + 3 * r->vt[r->start[v] + i];
            for (int k = 0; k < 3; k++)
                if (!p->active[t[k]])
                    p->active[t[k]] = 2;
        }
}

/* Around the active vertices (the corners of the round's merged fans, marked 1): flips over
 * them grown by a ring (marked 2), and one relaxation sweep under the bound over the corners
 * alone, each vertex keeping its offset from f = 0 (rm_relax.c). The next round's collapses
 * start from both. Relaxing the ring too (nearly every vertex moves in a sweep, each with
 * its fan measured): callgrind bench_error mesh S E 10 primal, simplification gyroid-ball
 * 0.0334 918M -> 832M without it, klein-bottle 0.0527 809M -> 777M, sphere 7.93e-4 and
 * torus 2.4e-3 -2%; triangles 7,914 -> 7,998, 10,842 -> 10,848, 4,148 -> 4,158, 2,302 ->
 * 2,320 (gyroid-ball 0.0181 8,298 -> 8,350, klein 0.0251 12,302 -> 12,308, sphere 1.98e-4
 * 16,696 -> 16,712, torus 6e-4 9,252 -> 9,282). The balancing offsets are set where a merge or a tried merge's ring puts
 * a vertex (sp_collapse.c, sp_trial.c); a sweep of them here as well cost 16% of the pass on
 * the sphere (callgrind, E 3e-3) for triangle counts within ±0.3% (sphere, torus, gyroid-ball
 * at E 1e-2, 3e-3, 1e-3: −10..+128 triangles, both ways). */
static void even_out(rm_pass *p, bool *ok)
{
    grow_active(p);
    rm_flip_active(p, ok);
    if (*ok)
        rm_relax_sweep(p, 1);
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
    sp_history h = {0};
    size_t nv = m->nverts, nt = m->ntris;
    bool ok = rm_pass_open(&p, m, o, 0) && sp_history_open(&h, &p);
    rm_found_offset_drop(&p); /* no records here (rm_brec.h) */
    p.bounded = true;
    if (ok) {
        p.memo = rm_memo_new(); /* NULL: every measure is taken afresh */
        p.flipped = h.flipped;
        memset(p.active, 1, m->nverts);
    }
    for (int round = 0; ok && round < ISM_SP_ROUNDS && !stopped(o); round++) {
        size_t live = live_vertices(&p);
        size_t made = sp_collapse_round(&p, &h, o->cancel, &ok);
        st->rounds++;
        if (ok && !stopped(o))
            even_out(&p, &ok);
        sp_history_flips(&h, m->nverts);
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
    rm_memo_free(p.memo);
    p.memo = NULL;
    p.flipped = NULL;
    sp_history_free(&h);
    if (!rm_pass_close(&p, nv, nt, ren))
        ok = false;
    st->triangles_after = m->ntris;
    st->min_angle_after = ism_remesh_min_angle(m);
    st->time_ms = ism_now_ms() - t0;
    return ok ? true : ism_error_set(err, "simplification: out of memory");
}
