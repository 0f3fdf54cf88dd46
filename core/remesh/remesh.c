/* remesh.c — the quality pass in order (remesh.h): ∇f normals, protection, then rounds of
 * Lawson flips (to a fixed point or the sweep limit), collapses of the needles left, one
 * relaxation, one sweep onto and along min/max creases (rm_crease_slide.c) and one slide
 * sweep, ending with flips so the last moves' quads are Delaunay too, a last mending of the
 * needles those leave and the thin tubes' tips merged into their points (rm_horn.c); then the
 * mesh is renumbered without what collapses removed. */
#include "core/remesh/remesh.h"
#include "core/remesh/rm_brec.h"
#include "core/remesh/rm_cbound.h"
#include "core/remesh/rm_hcell.h"
#include "core/remesh/rm_memo.h"
#include "core/remesh/rm_pass.h"
#include "core/util/clock.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Rounds of (flips, relaxation): the smallest angle rises fastest in the first few (sphere,
 * torus, pretzel-genus2 after 3 rounds: 33.3°, 24.6°, 24.4°; after 4: 33.7°, 25.5°, 24.9°;
 * after 8: 34.2°, 25.5°, 26.5°), and the work per round falls as fewer triangles stay poor. */
#define ISM_RM_ROUNDS 5
/* Collapses start in this round: the first rounds' flips and moves mend most needles, and
 * collapsing before them takes away vertices the relaxation would have spread out
 * (kummer-16-nodes: 284 collapses from round 2, 17,431 from round 0, for the same triangles
 * under 10°; steiner-roman in its box: 281 against 369 under 10°). */
#define ISM_RM_COLLAPSE_ROUND 2
/* From the round after the collapses' first, the rounds stop when the last one neither
 * raised the smallest angle nor took a triangle out from under ISM_RM_COLLAPSE_DEG: what
 * would follow only evens out angles the goals do not measure (pretzel-genus2 under its
 * default bound: 26.79° after each of rounds 1 to 4, and rounds 3 and 4 were 23% of the
 * relaxation's tries). */
#define ISM_RM_STOP_ROUND (ISM_RM_COLLAPSE_ROUND + 1)
/* A vertex whose relaxation step (toward its fan's centroid, in the tangent plane) is
 * shorter than this × its fan's mean edge, and whose fan has no triangle under
 * ISM_RM_COLLAPSE_DEG, stays where it is: the angles about it would turn by about that much
 * in radians, and it is tried again next round if its neighbours' moves take it farther from
 * its fan's centroid. Beside a needle every step counts: crossing-planes' 1e-3 box kept 9
 * needles under 10° (test_quality's GoalsUnderTheDefaultBound) when the insertions'
 * neighbours could not take their short steps. Under the default bound, of the moves 27% on
 * torus and 33% on pretzel-genus2 were that short, most in the last rounds. Callgrind,
 * --quality good, default bound, 1 thread, pass / polygonise with ISM_RM_STOP_ROUND: torus
 * 1.19 -> 0.95, pretzel-genus2 1.31 -> 0.94, cube-minus-ball 1.09 -> 1.00, gyroid-ball 0.82
 * -> 0.71; smallest angle torus 30.50 -> 29.06°, pretzel-genus2 26.79°, sphere 35.16 ->
 * 35.44°, gyroid-ball 20.09°, cube-minus-ball 15.01°, klein-bottle 13.94 -> 13.60°. Without
 * a bound only where f cannot crease (rm_pass.h may_crease): there beside a min/max crease
 * the short steps still mend needles (cube-minus-ball without a bound, in
 * test_remesh_needles' third box: 9 needles left beside the crease with the rule, at most 6
 * without). */
#define ISM_RM_MIN_STEP 0.05
/* The same for a vertex more than a ring away from every locked vertex and every triangle
 * under ISM_RM_INSERT_DEG (rm_relax.c far_from_features), under an error bound where f
 * cannot crease: there the short steps even out angles the goals do not measure.
 * Callgrind, --quality good, default bound, 1 thread, own box, ism_quality_pass:
 * chmutov-quartic 292.6M -> 275.8M, catenoid 56.0M -> 48.1M, torus 40.3M -> 33.7M, sphere
 * 6.47M -> 4.88M. cusp22_sweep.py (42 presets x 5 boxes, the default bound): smallest angle
 * sphere 31.9-33.1°, torus 20.7° (irrational box; 24.9° with 0.05), pretzel-genus2 21.0°,
 * catenoid 20.2°; cusp-a2 (three boxes) and whitney-umbrella (0.37-cell box) one to three
 * more triangles under 10°, each touching the singular point; none elsewhere. Where f may
 * crease the short steps are kept everywhere: 0.15 away from the locked crease vertices
 * alone took three-balls' own and 1e-3 boxes from 11.9° and 11.7° to a free 8.7° and 8.4°
 * needle. Without a bound too (the depth path, not swept): there the rule left a needle on
 * Steiner's double line (test_remesh_needles' steiner_no_needle_on_the_double_lines). Nor
 * within rm_relax.c's ISM_RM_FAR_POINT_EDGES mean edges of a given singular point (the cusp's
 * cone). */
#define ISM_RM_FAR_STEP 0.15

/* The caller's cancel flag is up: the pass stops between steps, its mesh valid. */
static bool stopped(const ism_remesh_options *o) { return o->cancel && *o->cancel; }

/* Once the junction collapses have taken a crowd, once more: the crease slides, the flips
 * and the collapses where a needle is left (a collapse renames a crowd's vertices and
 * re-fans its rim, so moves and clusters refused before are asked again). three-balls with
 * depth.max 5, 1e-3 box: the lower triple point's fan 6.65 -> 19.28° (the slides alone
 * 6.99°, with the flips 6.99°: the second collapse does it); the upper one keeps its 0.86°
 * (crowd28.md). Only runs whose first collapses took a crowd can change: in cusp22's sweep
 * three-balls' own / 1e-3 / 1e-4 boxes, 2 triangles fewer each. */
static void junction_settle(rm_pass *p, const ism_remesh_options *o, bool *ok)
{
    /* a cancel is asked between the steps, as the rounds ask it (revK 5) */
    if (!stopped(o) && rm_mark_active(p))
        rm_crease_slide_sweep(p);
    if (!stopped(o) && rm_mark_active(p))
        rm_flip_active(p, ok);
    /* p->poorest is what rm_mark_active took before the flips: they make no triangle worse
       than that (rm_pass.h), so a needle left is seen; no second rm_mark_active is needed */
    if (*ok && !stopped(o) && p->poorest < rm_insert_poor())
        rm_junction_collapse(p, ok);
}

void ism_remesh_renumber_free(ism_remesh_renumber *ren)
{
    free(ren->vert);
    free(ren->origin);
    memset(ren, 0, sizeof *ren);
}

/* Triangles whose smallest angle's sine is within this factor of the smallest sine so far
 * have their angle measured (an arc tangent): the sine alone orders them up to rounding. */
#define ISM_RM_SINE_TIE 1.000001

/* Triangle abc (smallest sine s, twice its area, longest side l) into the smallest angle so
 * far (worst, degrees) and the least sine: measured when it is not degenerate (the
 * analysis's rule) and its sine is within ISM_RM_SINE_TIE of the least. */
static inline void take(const double *a, const double *b, const double *c, double s,
                        double area, double l, double *least, double *worst)
{
    if (area > 1e-12 * l * l && s <= *least * ISM_RM_SINE_TIE) {
        *least = fmin(*least, s);
        *worst = fmin(*worst, rm_min_angle(a, b, c) * 180 / M_PI);
    }
}

/* The smallest angle of the pass's live triangles, as ism_remesh_min_angle reads the mesh
 * once the pass has closed (the same triangles, corners in the same order), from the sines
 * the pass keeps: the sides and area only of a triangle within ISM_RM_SINE_TIE of the least
 * sine so far (the figure does not depend on the order: a triangle taken in one order and
 * not in another has a sine, so an angle, beyond the least one's). */
static double pass_min_angle(rm_pass *p)
{
    const ism_mesh *m = p->r.m;
    double worst = 90, least = INFINITY;
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *v = m->tri + 3 * t;
        if (p->r.dead[t] || v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
            continue;
        double s = rm_tri_sine(p, (uint32_t)t);
        if (!(s <= least * ISM_RM_SINE_TIE))
            continue;
        const double *a = m->pos + 3 * v[0], *b = m->pos + 3 * v[1], *c = m->pos + 3 * v[2];
        double n[3], area = rm_cross(a, b, c, n);
        double l = fmax(rm_dist(a, b), fmax(rm_dist(b, c), rm_dist(c, a)));
        take(a, b, c, s, area, l, &least, &worst);
    }
    return worst;
}

/* ism_remesh_min_angle, and with sine every triangle's smallest sine into it (rm_min_sine
 * of its corners in order, bit for bit: what rm_mark_active would measure first). */
static double min_angle_of(const ism_mesh *m, double *sine)
{
    double worst = 90, least = INFINITY;
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *v = m->tri + 3 * t;
        const double *a = m->pos + 3 * v[0], *b = m->pos + 3 * v[1], *c = m->pos + 3 * v[2];
        double n[3], area = rm_cross(a, b, c, n);
        double ab = rm_dist(a, b), bc = rm_dist(b, c), ca = rm_dist(c, a);
        double s = rm_sine_of(area, ab, bc, ca), l = fmax(ab, fmax(bc, ca));
        if (sine)
            sine[t] = s;
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
            continue;
        take(a, b, c, s, area, l, &least, &worst);
    }
    return worst;
}

double ism_remesh_min_angle(const ism_mesh *m) { return min_angle_of(m, NULL); }

/* The mesh as the pass found it, kept until the pass ends: a mending may measure its
 * farthest edge midpoint (rm_midpoint_within); most passes never mend (the smooth presets'
 * needles are gone by round 2), and the midpoints are 3 in 5 of the distances measured
 * before the rounds. */
typedef struct found {
    double *pos;
    uint32_t *tri;
    size_t ntris;
} found;

static bool keep_found(found *k, const ism_mesh *m)
{
    k->ntris = m->ntris;
    k->pos = malloc((m->nverts ? m->nverts : 1) * 3 * sizeof *k->pos);
    k->tri = malloc((m->ntris ? m->ntris : 1) * 3 * sizeof *k->tri);
    if (k->pos && k->tri) {
        memcpy(k->pos, m->pos, m->nverts * 3 * sizeof *k->pos);
        memcpy(k->tri, m->tri, m->ntris * 3 * sizeof *k->tri);
    }
    return k->pos && k->tri;
}

static void drop_found(found *k)
{
    free(k->pos);
    free(k->tri);
    k->pos = NULL;
    k->tri = NULL;
}

/* The relaxation's reach (rm_relax_sweep's most): on a surface with nothing protected (f
 * cannot crease, no vertex locked: every vertex of a poor triangle can move itself) only the
 * vertices of triangles under ISM_RM_COMFORT_DEG (mark 1); elsewhere their neighbours too
 * (mark 2), which give the needles beside a protected vertex, that cannot move, room
 * (test_remesh_needles: cube-minus-ball beside its crease, the touching spheres' point,
 * cross-cap's pinch points keep needles without them). Callgrind, --quality good, default
 * bound, 1 thread, own / 1e-3 / irrational box: moves torus 2,342 / 2,384 / 2,335 -> 1,624 /
 * 1,653 / 1,672, pretzel-genus2 1,691 / 1,784 / 2,560 -> 1,089 / 1,123 / 1,585; smallest angle
 * torus 29.06 / 28.55 / 25.71 -> 27.25 / 27.18 / 24.90°, pretzel-genus2 26.79 / 23.66 / 21.42
 * -> 26.79 / 21.61 / 21.42°. */
static uint8_t relax_reach(const rm_pass *p)
{
    for (size_t v = 0; !p->may_crease && v < p->r.m->nverts; v++)
        if (p->r.locked[v] && p->r.count[v])
            return UINT8_MAX;
    return p->may_crease ? UINT8_MAX : 1;
}

/* Collapses, then insertions beside the needles collapses cannot reach, then flips of the
 * split needles' thin halves (from the split needles' corners only). The last mending's
 * collapses may also bend an edge past the crease angle where f's curvature accounts for
 * it (rm_pass.h bend_curvature): a tube thinner than its edges, that a few triangles go
 * round, can shed a needle no other way (cusp-a2 beside its cusp, 1e-3 box: a 4.09° needle
 * 2 E from it, none since; at-the-cusp ones 2.29° -> 6.33° at the least). Not in the
 * rounds: the moves and flips that follow work on the fans so bent, and beside a fold
 * tighter than the cells they leave needles of their own (Whitney's umbrella beside its y
 * axis, z = x²/y², bent 100°-140° per edge: 0.37-cell box 0 -> 1 needle under 10°, at its
 * pinch point 0 -> 3, when every mending could). */
static void mend_needles(rm_pass *p, bool last, bool *ok)
{
    if (!(p->poorest < rm_collapse_poor()))
        return; /* no triangle under ISM_RM_COLLAPSE_DEG since rm_mark_active looked */
    p->bend_curvature = last;
    rm_collapse_active(p, ok);
    p->bend_curvature = false;
    if (*ok && rm_insert_active(p, last, ok) && *ok)
        rm_flip_from(p, p->touched, ok);
}

bool ism_remesh_quality(ism_mesh *m, const ism_remesh_options *o, ism_remesh_stats *st,
                        ism_remesh_renumber *ren, ism_error *err)
{
    double t0 = ism_now_ms();
    memset(st, 0, sizeof *st);
    if (ren)
        memset(ren, 0, sizeof *ren);
    if (!o->f) {
        st->min_angle_before = ism_remesh_min_angle(m);
        return ism_error_set(err, "quality pass: no function to project onto");
    }
    rm_pass p;
    size_t nv = m->nverts, nt = m->ntris;
    /* the sines measured for the smallest angle before are the first rm_mark_active's
       (callgrind gyroid-ball: both measures of every triangle were 12.6M instructions), and
       the needles among them size the room for insertions (rm_pass.h) */
    double *found_sine = malloc((nt ? nt : 1) * sizeof *found_sine);
    st->min_angle_before = min_angle_of(m, found_sine);
    size_t needles = 0;
    double needle = rm_insert_poor();
    for (size_t t = 0; found_sine && t < nt; t++)
        needles += found_sine[t] < needle;
    bool ok = rm_pass_open(&p, m, o, nt / ISM_RM_INSERT_SHARE + ISM_RM_INSERT_MIN + needles);
    if (ok)
        rm_sine_open(&p, found_sine, found_sine ? nt : 0);
    else
        free(found_sine);
    /* under an error bound every step keeps it, measured at centroids and edge midpoints
       (rm_bound.h), whatever the mesh before: the simplified mesh's vertices sit off f = 0 */
    p.bounded = o->max_error > 0;
    /* under a bound the records (rm_brec.h) only where f cannot crease: across a min/max
       crease the measure jumps by more than the point moved, and a record spares a point it
       would refuse (test_remesh's gyroid ball, its third box: a centroid 0.00134 from f = 0,
       moved by 0.00123, measured 0.00520 against E 0.00520); on the creasing presets the
       records never paid past their trial anyway (rm_brec_pays: gyroid-ball, cube-minus-ball
       and schwarz-d dropped them after 512 points) */
    bool records = !o->measure_all_centroids && !(p.bounded && p.may_crease);
    found k = {0};
    if (ok && (!keep_found(&k, m) ||
               (records && !(p.bounded ? rm_brec_open(&p) : rm_cbound_open(&p)))))
        ok = false;
    /* under a bound every vertex's offset kept with its place where no records keep it
       (rm_offset_open; out of memory: each measured when asked): schwarz-p measured
       8,499 vertices where they stood through rm_bound_signed (callgrind, own box) */
    if (ok && p.bounded && !p.offset)
        rm_offset_open(&p);
    rm_found_offset_drop(&p); /* taken by rm_offset_open, or of no use */
    /* under a bound a move's vertex is measured by keep_offset, its fan's check and the
       offset kept (rm_relax.c), a flip's centroids again by the moves beside it: the
       simplification's point-keyed memo answers the repeats (NULL: measured afresh) */
    if (ok && p.bounded)
        p.memo = rm_memo_new();
    /* under a bound the Hessian cells bound second steps (rm_hcell.h; NULL: both taken) */
    if (ok && p.bounded)
        p.hcell = rm_hcell_new(&p);
    if (ok) {
        rm_collapse_bounds(&p, k.pos, k.tri, k.ntris);
        p.relax_min_step = p.bounded || !p.may_crease ? ISM_RM_MIN_STEP : 0;
        p.relax_far_step = p.bounded && !p.may_crease ? fmax(ISM_RM_FAR_STEP, p.relax_min_step)
                                                      : p.relax_min_step;
        p.points = o->locked_points;
        p.npoints = o->nlocked_points;
        uint8_t reach = relax_reach(&p);
        double was_poorest = 0;
        size_t was_poor = 0;
        for (int round = 0; round < ISM_RM_ROUNDS && !stopped(o); round++) {
            if (!rm_mark_active(&p))
                break;
            if (round >= ISM_RM_STOP_ROUND && !(p.poorest > was_poorest) && !(p.poor < was_poor))
                break; /* the last round changed nothing the goals measure */
            was_poorest = p.poorest;
            was_poor = p.poor;
            /* the flips' corners: only their fans change, and only a crease's verdict with them
               (a flip takes a free edge and makes one, keeps every fan closed and every edge
               that holds a vertex: where f cannot crease nothing changes; torus 3.95M
               instructions of its pass) */
            if (round == 0 && p.may_crease)
                ok = (p.flipped = calloc(p.r.cap_verts ? p.r.cap_verts : 1, 1)) != NULL;
            if (ok && rm_flip_active(&p, &ok) && p.flipped)
                rm_lock_vertices(&p, o, p.flipped); /* caps flipped away: false creases go */
            if (ok && round == 0)
                rm_crease_lock_on(&p);
            free(p.flipped);
            p.flipped = NULL;
            if (!ok || stopped(o))
                break;
            if (round >= ISM_RM_COLLAPSE_ROUND)
                mend_needles(&p, false, &ok);
            if (!ok || stopped(o))
                break;
            size_t moved = rm_unfold_sweep(&p) + rm_relax_sweep(&p, reach);
            /* vertices beside a min/max crease go onto it once the collapses have had the
               crowded ones (bench_remesh gyroid-ball from round 0: 43 / 50 / 86 needles but
               smallest angle 0.53 / 0.58 / 1.05°, merges along the crease refused beside
               vertices just moved; from ISM_RM_COLLAPSE_ROUND: 54 / 51 / 86, 2.97 / 2.97 /
               0.40°) */
            if (round >= ISM_RM_COLLAPSE_ROUND)
                moved += rm_crease_slide_sweep(&p);
            if (!(moved + rm_slide_sweep(&p)))
                break;
        }
        if (ok && rm_mark_active(&p))
            rm_flip_active(&p, &ok);
        /* the last relaxation and flips leave needles of their own (merges that pass every
           test, unseen since the last collapse sweep): klein-bottle 2 / 2 / 1 triangles
           under 10° in its own / 1e-3 / 0.37-cell boxes -> 0, kummer-16 0.37-cell 16 -> 1 */
        if (ok && !stopped(o))
            mend_needles(&p, true, &ok);
        /* needles among crowded crease points, where three or more sheets meet and beside:
           no single merge passes there, the whole cluster collapses into one of its vertices
           (rm_junction.c) */
        if (ok && !stopped(o) && p.may_crease && p.poorest < rm_insert_poor() &&
            rm_junction_collapse(&p, &ok) && ok && !stopped(o))
            junction_settle(&p, o, &ok);
        /* a junction's fan left with a needle and without a vertex on one of its creases
           (rm_junction_fan.c), whether or not a crowd collapsed: three-balls -d 3:5, 1e-3 box,
           upper triple point 0.86° -> 22.67° */
        if (ok && !stopped(o) && p.may_crease)
            rm_junction_fan_mend(&p, &ok);
        /* what no mending could shape, thin tubes ending at a given point: merged into it */
        if (ok && !stopped(o))
            rm_horn_tips(&p, o, &ok);
        for (size_t v = 0; v < m->nverts; v++)
            st->locked_vertices += p.r.locked[v] && p.r.count[v];
    }
    drop_found(&k);
    rm_memo_free(p.memo);
    p.memo = NULL;
    rm_hcell_free(p.hcell);
    p.hcell = NULL;
    double after = ok && p.r.dead ? pass_min_angle(&p) : NAN;
    st->flips = p.flips;
    st->moves = p.moves;
    st->collapses = p.collapses;
    st->inserts = p.inserts;
    if (!rm_pass_close(&p, nv, nt, ren))
        ok = false;
    st->min_angle_after = isnan(after) ? ism_remesh_min_angle(m) : after;
    st->time_ms = ism_now_ms() - t0;
    return ok ? true : ism_error_set(err, "quality pass: out of memory");
}
