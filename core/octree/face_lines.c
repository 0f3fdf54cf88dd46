/* face_lines.c — the lines of f = 0 on one tile of a node's face (paper §2: LineOnFace,
 * LineOnFaceAndEdge, DoubleIntersectsOnEdges). The tile's boundary is walked over its
 * lattice segments; the roots found there (crossings, tangent roots, zero lattice points)
 * become events with the sign of f on either side, and the events are joined into lines:
 *   - crossings in pairs: one pair directly; two or more pairs by the paper's gradient dot
 *     products (a curve's two ends see the same sheet), the face centre's sign breaking
 *     ties, or as two crossing lines when two sheets intersect inside the tile;
 *   - tangent roots in pairs along a double line lying in the face (self-intersection on
 *     the face, paper Fig. 3b), confirmed by the double-root search across its middle;
 *   - a tangent root or zero point at the apex of a wedge between two sheets joins the two
 *     crossings around it (paper Fig. 3c);
 *   - lattice segments where f vanishes are lines of their own (double lines on edges).
 * Everything here depends only on the tile, so both nodes that share it agree, and the
 * second of them copies the first one's lines (cell_cache.h: the tile memo). */
#include "core/octree/face_lines.h"
#include "core/octree/face_flat.h"
#include "core/octree/root_table.h"
#include "core/octree/singular.h"
#include "core/octree/tile_corners.h"
#include "core/util/grow.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Crossings (and, apart, tangent roots) one tile can join. A tile of a node that passed the
 * flatness test is cut by one curve, or two where sheets cross (2 to 4 crossings); only a
 * leaf at the maximum depth that failed it sees more, and 64 means 32 curves through one
 * tile — an f oscillating far below the cell size. Past it the extra events are dropped: the lines
 * through them are missing, which shows as open chains (counted, open_chains) where the
 * neighbouring face kept its end. */
#define MAX_CROSS 64
/* Points sampled on the straight path between two arcs of one sign (arcs_joined): a region
 * of the other sign must cross the path to part them. 15 samples, 1/16 of the path apart,
 * see any such band wider than that; a thinner one is finer than the tile resolves, and
 * each sample is one evaluation of f on every tile with 4 crossings. */
#define JOIN_SAMPLES 15
/* A bent path between two arcs whose points lie on one side (arcs_joined_around) turns at
 * k/8 of the tile's extent across that side, k = 1..7: a band of the arcs' sign between the
 * other sign's bump and its region beyond is found when it is 1/8 of the tile wide; 14 paths
 * of 2 × JOIN_SAMPLES points at most, on the rare tile where no straight path decides. */
#define BENT_STEPS 8
/* A zero lattice point's `before` sign is known only after the walk (the gap after the
 * previous event): this marks it until then; never a sign (+1, -1, 0). */
#define SIGN_UNKNOWN 99
/* Where an X's chords meet, two crossing sheets make f singular: |f| there at most this
 * fraction of (mean |∇f| at the four crossings × tile size) — the point is on the surface
 * to 5% of the tile, first order — ... */
#define X_CENTRE_F_FRAC 0.05
/* ... and |∇f| there at most this fraction of that mean: between two parallel sheets close
 * together (which pass the other tests) ∇f is as large as anywhere, while at a crossing it
 * vanishes; a quarter leaves room for the X's centre being a chord intersection, not the
 * exact singular point. */
#define X_CENTRE_GRAD_FRAC 0.25
/* The double-root search across the middle of two tangent roots probes ±this fraction of
 * their distance to either side: far enough to leave a double line's narrow neighbourhood
 * of one sign, near enough to stay on the tile between them. */
#define DOUBLE_LINE_PROBE 0.25
/* A wedge's bisector shorter than this (unit arms nearly opposite, an opening of ~180°) is
 * no wedge: the apex is a point on one smooth curve. */
#define WEDGE_MIN_BISECTOR 1e-6
/* The wedge is probed this fraction of the tile size along its bisector (inside the wedge,
 * outside the rounding of the apex), and never beyond this fraction of its shorter arm (so
 * the probe stays between the two curves). */
#define WEDGE_PROBE_FRAC 0.02
#define WEDGE_PROBE_ARM 0.25
/* Two families of lines whose gradient scores (the sum over their lines of the dot product
 * of the unit gradients at a line's two ends: 1 each when the ends see one sheet) differ by
 * less than this per line are a tie, broken by the centre's sign. */
#define FAMILY_SCORE_MARGIN 0.1

bool ism_flines_push(ism_flines *l, const ism_fpoint *a, const ism_fpoint *b, int kind)
{
    if (!ism_grow((void **)&l->v, &l->cap, l->n + 1, sizeof *l->v, 32))
        return false;
    ism_fline *ln = &l->v[l->n++];
    ln->a = *a;
    ln->b = *b;
    ln->kind = (uint8_t)kind;
    return true;
}

/* A lattice point's key hashed once serves every table it is looked up in (the memo below,
 * the build's corner memo, the break-point registry): each masks ism_cache_mix(key). */
static ism_lattice_entry *lattice_slot(ism_cell_ctx *cx, uint64_t hash)
{
    return &cx->cache.points[hash & (((uint64_t)1 << ISM_POINT_CACHE_BITS) - 1)];
}

/* Lattice point ip through the thread's memo: f and ∇f there, and its successors on its
 * lattice lines from the break-point registry (one probe there per memo miss). f is 0 where
 * its sign is rounding noise (ism_sample_zero_by_rounding): a zero point for every tile that
 * meets it
 * (the sphere r = 1.5 in the box ±1.6 has f = +4.4e-16 at (0.2, 0.5, -1.4): each lattice
 * segment from there found a root 1e-15 away, the one node on the negative side cut off its
 * corner by a triangle of those three roots lying in its lower face in floating point, which
 * that face's owner never emits: a hole of three zero-length edges at each such point). */
static __attribute__((noinline)) const ism_lattice_entry *
lattice_fill(ism_cell_ctx *cx, ism_lattice_entry *e, const int32_t ip[3], uint64_t key,
             uint64_t hash)
{
    if (e->key != key) {
        double p[3];
        __builtin_prefetch(ism_breaks_slot(cx->breaks, hash));
        ism_grid_point(&cx->tree->grid, (ism_ipt){{ip[0], ip[1], ip[2]}}, p);
        e->key = key;
        /* the build's value when it evaluated the point (the same bits: f and ∇f there are
         * pure, and every tape either side uses gives f's own inside its box, sampler.h) */
        const ism_point_entry *c =
            cx->corners ? ism_point_find_hashed(cx->corners, ISM_CORNER_MEMO_BITS, key, hash)
                        : NULL;
        if (c) {
            e->f = c->f;
            memcpy(e->g, c->g, sizeof e->g);
            cx->corner_values++;
        } else {
            e->f = ism_sample_grad(&cx->s, p, e->g);
        }
        e->gn = ism_norm3(e->g);
        const double *st = cx->tree->grid.step;
        if (e->f != 0 && ism_sample_zero_by_rounding(&cx->s, p, e->f, e->gn,
                                                     fmin(st[0], fmin(st[1], st[2]))))
            e->f = 0;
        e->round = 0;
    }
    if (e->round != cx->cache.round) { /* f and ∇f from an earlier round still hold */
        const ism_break_point *b = ism_breaks_find_hashed(cx->breaks, key, hash);
        for (int a = 0; a < 3; a++)
            e->next[a] = b ? b->next[a] : ISM_LATTICE_UNREGISTERED;
        e->round = cx->cache.round;
    }
    return e;
}

/* lattice_fill, asked only when the memo's entry does not hold the point for this round (a
 * hit returns it directly). */
static inline const ism_lattice_entry *lattice_entry(ism_cell_ctx *cx, const int32_t ip[3])
{
    uint64_t key = ism_lattice_key(ip), hash = ism_cache_mix(key);
    ism_lattice_entry *e = lattice_slot(cx, hash);
    if (e->key == key && e->round == cx->cache.round)
        return e;
    return lattice_fill(cx, e, ip, key, hash);
}

/* Room for one more boundary point: its slot at the end of cx->bp (counted), or NULL when
 * memory runs out. */
static inline ism_bpoint *bpoint_reserve(ism_cell_ctx *cx)
{
    if (!ism_grow((void **)&cx->bp, &cx->cap_bp, cx->nbp + 1, sizeof *cx->bp, 64))
        return NULL;
    return &cx->bp[cx->nbp++];
}

/* b as lattice point ip, at world position p, of the boundary with f and ∇f from its memo
 * entry e (just asked for: the entry is copied before another lookup may take its slot). */
static inline void bpoint_fill_at(ism_bpoint *b, const int32_t ip[3], const double p[3],
                                  const ism_lattice_entry *e, bool ascending)
{
    memcpy(b->ip, ip, sizeof b->ip);
    b->ascending = ascending;
    memcpy(b->p, p, sizeof b->p);
    b->f = e->f;
    memcpy(b->g, e->g, sizeof b->g);
    b->gn = e->gn;
}

/* bpoint_fill_at with ip's world position from the grid. */
static inline void bpoint_fill(const ism_cell_ctx *cx, ism_bpoint *b, const int32_t ip[3],
                               const ism_lattice_entry *e, bool ascending)
{
    double p[3];
    ism_grid_point(&cx->tree->grid, (ism_ipt){{ip[0], ip[1], ip[2]}}, p);
    bpoint_fill_at(b, ip, p, e, ascending);
}

/* Appends a lattice point of the boundary (bpoint_fill). */
static bool push_bpoint(ism_cell_ctx *cx, const int32_t ip[3], const ism_lattice_entry *e,
                        bool ascending)
{
    ism_bpoint *b = bpoint_reserve(cx);
    if (!b)
        return false;
    bpoint_fill(cx, b, ip, e, ascending);
    return true;
}

/* A corner of the tile as the walk needs it: its boundary point and its successors on its
 * lattice lines (copied: its memo entry may be taken by a later lookup). */
typedef struct tile_corner {
    ism_bpoint b;
    int32_t next[3];
} tile_corner;

/* Appends the break points strictly between corner c, the side's lower end, and coordinate
 * hi along `along`, found ascending through the registry's successors (one memo lookup a
 * point, each pushed as it is found); reversed after when the side is walked downward.
 * False when a point the registry gave is unregistered in the memo (a bug; cx->unregistered
 * is then set), or when memory runs out. (Corner c itself was checked registered by
 * tile_boundary.) */
static bool side_points(ism_cell_ctx *cx, int along, const tile_corner *c, int32_t hi, bool up)
{
    int32_t q[3] = {c->b.ip[0], c->b.ip[1], c->b.ip[2]};
    size_t first = cx->nbp;
    for (int32_t x = c->next[along]; x < hi;) {
        q[along] = x;
        const ism_lattice_entry *e = lattice_entry(cx, q);
        if (e->next[0] == ISM_LATTICE_UNREGISTERED) {
            cx->unregistered = true;
            return false;
        }
        if (!push_bpoint(cx, q, e, up))
            return false;
        x = e->next[along];
    }
    for (size_t i = first, j = cx->nbp; !up && i + 1 < j; i++, j--) {
        ism_bpoint b = cx->bp[i];
        cx->bp[i] = cx->bp[j - 1];
        cx->bp[j - 1] = b;
    }
    return true;
}

/* side_points, asked only when the side holds a point between its corners (most sides hold
 * none: their lower corner's successor is the upper one). */
static inline bool side_between(ism_cell_ctx *cx, int along, const tile_corner *c, int32_t hi,
                                bool up)
{
    return c->next[along] >= hi || side_points(cx, along, c, hi, up);
}

static inline bool push_corner(ism_cell_ctx *cx, const tile_corner *c)
{
    ism_bpoint *b = bpoint_reserve(cx);
    if (!b)
        return false;
    *b = c->b;
    return true;
}

static inline bool rootless(const ism_cell_ctx *cx, const ism_bpoint *lo,
                            const ism_bpoint *hi);

/* Is the tile quiet by its corners alone: no break point between them, none a zero point, and
 * each side rootless in its canonical direction (the first two sides run up from corners 0
 * and 1, the last two down to corners 3 and 0)? Then its walk finds no event (tile_events:
 * every segment is a side, skipped as rootless, and no zero point starts one), exactly. */
static bool quiet_by_corners(const ism_cell_ctx *cx, const ism_tile *t, int u, int v,
                             const tile_corner c[4])
{
    bool neg = c[0].b.f < 0; /* a side between signs is never rootless: not tested */
    return c[0].next[u] >= t->u1 && c[1].next[v] >= t->v1 && c[3].next[u] >= t->u1 &&
           c[0].next[v] >= t->v1 && c[0].b.f != 0 && c[1].b.f != 0 && c[2].b.f != 0 &&
           c[3].b.f != 0 && (c[1].b.f < 0) == neg && (c[2].b.f < 0) == neg &&
           (c[3].b.f < 0) == neg && rootless(cx, &c[0].b, &c[1].b) &&
           rootless(cx, &c[1].b, &c[2].b) && rootless(cx, &c[3].b, &c[2].b) &&
           rootless(cx, &c[0].b, &c[3].b);
}

/* Walks the tile boundary counter-clockwise in (u, v), collecting every break point: each
 * side from its first corner toward the next, which is left out (it starts the next side).
 * The four corners are looked up once each (a side's points between its corners follow
 * from its lower corner's successors). A side's lower corner is a corner of a non-empty
 * leaf (every side of a tile is an edge of one), so it is registered: false when it is not
 * (a bug; cx->unregistered is then set), or when memory runs out. *quiet: the tile is quiet
 * by its corners alone (quiet_by_corners), and then nothing is collected, but under
 * walk_every_tile (which walks it to check that answer: check_by_corners). */
static bool tile_boundary(ism_cell_ctx *cx, const ism_tile *t, bool *quiet)
{
    int u = ism_axis_next(t->axis), v = ism_axis_prev(t->axis);
    tile_corner c[4];
    int32_t q[4][3];
    double p[4][3];
    ism_tile_corners(t, q);
    ism_tile_corner_points(&cx->tree->grid, t, p);
    for (int k = 0; k < 4; k++) {
        const ism_lattice_entry *e = lattice_entry(cx, q[k]);
        /* sides 0 and 1 run up u and v, 2 and 3 down */
        bpoint_fill_at(&c[k].b, q[k], p[k], e, k < 2);
        memcpy(c[k].next, e->next, sizeof c[k].next);
    }
    /* the sides' lower corners: 0 (sides 0 and 3), 1 (side 1), 3 (side 2) */
    if (c[0].next[0] == ISM_LATTICE_UNREGISTERED || c[1].next[0] == ISM_LATTICE_UNREGISTERED ||
        c[3].next[0] == ISM_LATTICE_UNREGISTERED) {
        cx->unregistered = true;
        return false;
    }
    cx->nbp = 0;
    *quiet = quiet_by_corners(cx, t, u, v, c);
    if (*quiet && !cx->walk_every_tile)
        return true;
    return push_corner(cx, &c[0]) && side_between(cx, u, &c[0], t->u1, true) &&
           push_corner(cx, &c[1]) && side_between(cx, v, &c[1], t->v1, true) &&
           push_corner(cx, &c[2]) && side_between(cx, u, &c[3], t->u1, false) &&
           push_corner(cx, &c[3]) && side_between(cx, v, &c[0], t->v1, false);
}

static bool push_event(ism_cell_ctx *cx, const ism_fpoint *pt, int before, int after, size_t seg)
{
    if (!ism_grow((void **)&cx->ev, &cx->cap_ev, cx->nev + 1, sizeof *cx->ev, 64))
        return false;
    cx->ev[cx->nev++] = (ism_fevent){*pt, before, after, (int)seg};
    return true;
}

static ism_fpoint root_point(const ism_root *r, uint8_t flags)
{
    ism_fpoint q;
    memcpy(q.p, r->p, sizeof q.p);
    memcpy(q.g, r->g, sizeof q.g);
    q.flags = flags;
    return q;
}

static void compute_segment(ism_cell_ctx *cx, const ism_bpoint *lo, const ism_bpoint *hi,
                            uint64_t ka, uint64_t kb, ism_seg_roots *out);

/* Is a→b, a's segment of the boundary, the segment's canonical direction (increasing
 * lattice coordinate)? Known from the side a lies on (tile_boundary). */
static bool is_forward(const ism_bpoint *a)
{
    return a->ascending;
}

static ism_segment_entry *segment_entry(ism_cell_ctx *cx, uint64_t ka, uint64_t kb)
{
    return &cx->cache.segments[ism_cache_mix(ka * 31 + kb) &
                               (((uint64_t)1 << ISM_SEGMENT_CACHE_BITS) - 1)];
}

/* A segment whose end values prove it rootless (in its canonical direction lo→hi, as
 * compute_segment asks): no memo lookup (a cache miss) for it. Inline, along the one axis
 * the two lattice points differ on (ism_lattice_segment_rootless: out of line, the call and
 * the full dot products cost Klein's bottle at E 3.27e-3 about a third of this test). */
static inline bool rootless(const ism_cell_ctx *cx, const ism_bpoint *lo, const ism_bpoint *hi)
{
    int axis = lo->ip[0] != hi->ip[0] ? 0 : lo->ip[1] != hi->ip[1] ? 1 : 2;
    return ism_lattice_segment_rootless(&cx->roots, axis, lo->p, hi->p, lo->f, hi->f, lo->g,
                                        hi->g, lo->gn, hi->gn);
}

/* What the walk keeps of a boundary point between its two passes (tile_events): the memo
 * slot of its segment to the next point and that segment's keys, found once (the slot is
 * asked for from memory in the first pass, read in the second), and the sign of f just
 * after the point. */
typedef struct ism_walk_gap {
    ism_segment_entry *seg; /* NULL: the segment is rootless (no slot looked at) */
    uint64_t ka, kb;        /* with seg: its lower and upper lattice keys */
    int sign;
} ism_walk_gap;

/* Fills gap's segment a→b: its memo slot and keys, the slot asked for from memory (the walk
 * reads it soon after), or none when the segment is rootless and needs none. */
static void ask_segment(ism_cell_ctx *cx, const ism_bpoint *a, const ism_bpoint *b,
                        ism_walk_gap *gap)
{
    bool forward = is_forward(a);
    const ism_bpoint *lo = forward ? a : b, *hi = forward ? b : a;
    if (rootless(cx, lo, hi)) {
        gap->seg = NULL;
        return;
    }
    gap->ka = ism_lattice_key(lo->ip);
    gap->kb = ism_lattice_key(hi->ip);
    gap->seg = segment_entry(cx, gap->ka, gap->kb);
    __builtin_prefetch(gap->seg, 1);
}

/* No root (a rootless segment's answer). */
static const ism_seg_roots no_roots = {0, 0, {{0}}};

/* Roots of the segment a→b in walking order, computed in the canonical direction into its
 * memo slot (gap, from ask_segment; none without a look when it has none): the slot's own
 * roots, or *rev when they are two walked downward (there reversed). The answer is read
 * before the memo is asked again. */
static inline __attribute__((always_inline)) const ism_seg_roots *
walk_segment(ism_cell_ctx *cx, const ism_bpoint *a, const ism_bpoint *b,
             const ism_walk_gap *gap, ism_seg_roots *rev)
{
    ism_segment_entry *e = gap->seg;
    if (!e)
        return &no_roots;
    bool forward = is_forward(a);
    if (e->a != gap->ka || e->b != gap->kb) {
        compute_segment(cx, forward ? a : b, forward ? b : a, gap->ka, gap->kb, &e->roots);
        e->a = gap->ka;
        e->b = gap->kb;
    }
    if (forward || e->roots.n != 2)
        return &e->roots;
    *rev = e->roots;
    rev->r[0] = e->roots.r[1];
    rev->r[1] = e->roots.r[0];
    return rev;
}

/* The roots of the canonical segment lo→hi, with two roots closer than the stitching
 * tolerance merged into one double root (paper Fig. 3b) when f between them stays within
 * the double-root eps — the search's own rule for a touching root: two sheets crossing just
 * off the segment (x² − y² at y = δ: f = −δ² between roots 2δ apart), a double line the
 * face's walk then sees lying in it. Where f between them goes beyond eps, the other sign
 * holds a piece of its own and both crossings stay: the tip of a CSG bar's section grazed
 * by the segment (cube minus ball r = 1.41, 0.37 of a cell off the lattice at depth 7: roots
 * 2e-6 apart, f −1e-6 between; merged, both faces at that edge joined their two crossings
 * through the one touching point, and the node's loop passed through it twice). */
static void compute_segment(ism_cell_ctx *cx, const ism_bpoint *lo, const ism_bpoint *hi,
                            uint64_t ka, uint64_t kb, ism_seg_roots *out)
{
    /* a single root the octree build searched on this edge (root_table.h): not again */
    double t;
    bool known = (lo->f < 0) != (hi->f < 0) && ism_root_table_find(cx->found, ka, kb, &t);
    ism_segment_roots(&cx->s, &cx->roots, lo->p, hi->p, lo->f, hi->f, lo->g, hi->g,
                      known ? &t : NULL, out);
    if (out->n == 2 && out->r[1].t - out->r[0].t < cx->stitch_tol) {
        ism_root m = out->r[0];
        m.t = 0.5 * (out->r[0].t + out->r[1].t);
        for (int k = 0; k < 3; k++)
            m.p[k] = lo->p[k] + m.t * (hi->p[k] - lo->p[k]);
        if (!(fabs(ism_sample_grad(&cx->s, m.p, m.g)) < cx->roots.eps))
            return; /* two sign changes, a piece between them */
        m.kind = ISM_ROOT_TOUCH;
        out->r[0] = m;
        out->n = 1;
    }
}

/* Sign of f along a segment with no roots whose ends may be zero (0 if f vanishes there). */
static int rootless_sign(ism_cell_ctx *cx, const ism_bpoint *a, const ism_bpoint *b)
{
    if (a->f != 0)
        return ism_sign(a->f);
    if (b->f != 0)
        return ism_sign(b->f);
    double m[3];
    for (int k = 0; k < 3; k++)
        m[k] = 0.5 * (a->p[k] + b->p[k]);
    double fm = ism_sample_f(&cx->s, m);
    return fabs(fm) <= cx->roots.eps ? 0 : ism_sign(fm);
}

/* Turns the boundary into events with the sign of f on both sides of each. Inlined in its
 * one caller, walk_tile, which grew past GCC's own limit with check_by_corners (out of line:
 * Klein 0.0141 +0.3M instructions). */
static inline __attribute__((always_inline)) bool tile_events(ism_cell_ctx *cx)
{
    cx->nev = 0;
    size_t n = cx->nbp;
    if (cx->cap_gap < n) {
        ism_walk_gap *v = realloc(cx->gap, n * sizeof *v);
        if (!v)
            return false;
        cx->gap = v;
        cx->cap_gap = n;
    }
    ism_walk_gap *gap = cx->gap;
    for (size_t i = 0; i < n; i++)
        ask_segment(cx, &cx->bp[i], &cx->bp[i + 1 < n ? i + 1 : 0], &gap[i]);
    /* first pass: the sign just after each lattice point and the roots on its segment */
    for (size_t i = 0; i < n; i++) {
        const ism_bpoint *a = &cx->bp[i], *b = &cx->bp[i + 1 < n ? i + 1 : 0];
        ism_seg_roots rev;
        const ism_seg_roots *r = walk_segment(cx, a, b, &gap[i], &rev);
        int sa = ism_sign(a->f), sb = ism_sign(b->f);
        uint8_t many = r->flags & ISM_SEG_MANY_ROOTS ? ISM_FP_MANY : 0;
        if (r->n == 0) {
            gap[i].sign = rootless_sign(cx, a, b);
        } else {
            gap[i].sign = sa;
        }
        if (a->f == 0) {
            ism_fpoint z;
            memcpy(z.p, a->p, sizeof z.p);
            memcpy(z.g, a->g, sizeof z.g);
            z.flags = ISM_FP_ZERO;
            if (!push_event(cx, &z, SIGN_UNKNOWN, gap[i].sign, i)) /* filled below */
                return false;
        }
        if (r->n == 1 && r->r[0].kind == ISM_ROOT_CROSS) {
            ism_fpoint q = root_point(&r->r[0], many);
            if (!push_event(cx, &q, sa, sb, i))
                return false;
        } else if (r->n == 1) {
            ism_fpoint q = root_point(&r->r[0], ISM_FP_TOUCH | many);
            if (!push_event(cx, &q, sa, sa, i))
                return false;
        } else if (r->n == 2) {
            ism_fpoint q0 = root_point(&r->r[0], ISM_FP_PAIR | many);
            ism_fpoint q1 = root_point(&r->r[1], ISM_FP_PAIR | many);
            if (!push_event(cx, &q0, sa, -sa, i) || !push_event(cx, &q1, -sa, sa, i))
                return false;
        }
    }
    /* second pass: a zero point's `before` is the gap after the previous event */
    for (size_t k = 0; k < cx->nev; k++)
        if (cx->ev[k].before == SIGN_UNKNOWN) {
            size_t prev = (k + cx->nev - 1) % cx->nev;
            cx->ev[k].before = cx->ev[prev].after;
            if (cx->nev == 1)
                cx->ev[k].before = cx->ev[k].after;
        }
    return true;
}

static double unit_dot(const double a[3], const double b[3])
{
    double na = ism_norm3(a), nb = ism_norm3(b);
    if (!(na > 0) || !(nb > 0) || !isfinite(na * nb))
        return 0;
    return ism_dot3(a, b) / (na * nb);
}

static void tile_centre(const ism_cell_ctx *cx, const ism_tile *t, double c[3])
{
    const ism_grid *g = &cx->tree->grid;
    int u = ism_axis_next(t->axis), v = ism_axis_prev(t->axis);
    c[t->axis] = ism_grid_coord(g, t->axis, t->plane);
    c[u] = 0.5 * (ism_grid_coord(g, u, t->u0) + ism_grid_coord(g, u, t->u1));
    c[v] = 0.5 * (ism_grid_coord(g, v, t->v0) + ism_grid_coord(g, v, t->v1));
}

static double tile_size(const ism_cell_ctx *cx, const ism_tile *t)
{
    const ism_grid *g = &cx->tree->grid;
    int u = ism_axis_next(t->axis), v = ism_axis_prev(t->axis);
    double su = g->step[u] * (t->u1 - t->u0), sv = g->step[v] * (t->v1 - t->v0);
    return su < sv ? su : sv;
}

/* Where segments p0p1 and q0q1 (in the tile's plane) cross; false if they don't. */
static bool chords_cross(const ism_tile *t, const double p0[3], const double p1[3],
                         const double q0[3], const double q1[3], double x[3])
{
    int u = ism_axis_next(t->axis), v = ism_axis_prev(t->axis);
    double du = p1[u] - p0[u], dv = p1[v] - p0[v], eu = q1[u] - q0[u], ev = q1[v] - q0[v];
    double den = du * ev - dv * eu;
    if (den == 0)
        return false;
    double s = ((q0[u] - p0[u]) * ev - (q0[v] - p0[v]) * eu) / den;
    double r = ((q0[u] - p0[u]) * dv - (q0[v] - p0[v]) * du) / den;
    if (s <= 0 || s >= 1 || r <= 0 || r >= 1)
        return false;
    for (int k = 0; k < 3; k++)
        x[k] = p0[k] + s * (p1[k] - p0[k]);
    return true;
}

/* Two sheets crossing inside the tile (an X): the opposite crossings lie on one sheet each
 * (parallel or anti-parallel gradients), and where the two chords meet f vanishes and so
 * does its gradient (where two sheets cross, f is singular). Two parallel sheets close
 * together pass the first tests but not the last: between them ∇f is as large as anywhere. */
static bool is_crossing_x(ism_cell_ctx *cx, const ism_tile *t, ism_fevent *k[4], double x[3])
{
    double gt = cx->roots.gradient_test;
    if (fabs(unit_dot(k[0]->pt.g, k[2]->pt.g)) < gt || fabs(unit_dot(k[1]->pt.g, k[3]->pt.g)) < gt)
        return false;
    if (!chords_cross(t, k[0]->pt.p, k[2]->pt.p, k[1]->pt.p, k[3]->pt.p, x))
        return false;
    double gbar = 0;
    for (int i = 0; i < 4; i++)
        gbar += ism_norm3(k[i]->pt.g) / 4;
    double g[3];
    double f = ism_sample_grad(&cx->s, x, g);
    return fabs(f) <= X_CENTRE_F_FRAC * gbar * tile_size(cx, t) &&
           ism_norm3(g) <= X_CENTRE_GRAD_FRAC * gbar;
}

/* Where the X's lines meet (x): a singular point of the face (the same tile gives the same
 * point to both nodes that share it), a cone's apex just off the face, or neither — see
 * ism_plane_crossing. */
static int tile_plane_crossing(ism_cell_ctx *cx, const ism_tile *t, const double x[3],
                               ism_fpoint *apex)
{
    const ism_grid *g = &cx->tree->grid;
    int u = ism_axis_next(t->axis), v = ism_axis_prev(t->axis);
    double lo[2] = {ism_grid_coord(g, u, t->u0), ism_grid_coord(g, v, t->v0)};
    double hi[2] = {ism_grid_coord(g, u, t->u1), ism_grid_coord(g, v, t->v1)};
    return ism_plane_crossing(&cx->s, t->axis, x, lo, hi, apex);
}

/* The paper's double-root search across the middle of t1t2: a double line lies on the face
 * between two tangent roots when f touches 0 there too. */
static bool double_line_between(ism_cell_ctx *cx, const ism_tile *t, const ism_fpoint *t1,
                                const ism_fpoint *t2)
{
    double d[3], w[3], m[3], a[3], b[3];
    for (int k = 0; k < 3; k++) {
        d[k] = t2->p[k] - t1->p[k];
        m[k] = 0.5 * (t1->p[k] + t2->p[k]);
    }
    double len = ism_norm3(d);
    if (!(len > 0))
        return false;
    double nrm[3] = {0, 0, 0};
    nrm[t->axis] = 1;
    ism_cross3(nrm, d, w);
    ism_normalise3(w);
    double half = DOUBLE_LINE_PROBE * len;
    for (int k = 0; k < 3; k++) {
        a[k] = m[k] - half * w[k];
        b[k] = m[k] + half * w[k];
    }
    double fa = ism_sample_f(&cx->s, a), fb = ism_sample_f(&cx->s, b);
    double fm = ism_sample_f(&cx->s, m);
    if (fabs(fm) < cx->roots.eps)
        return true;
    if (fa * fb <= 0)
        return false;
    double tc;
    return ism_double_root_search(&cx->s, &cx->roots, a, b, fa, fb, &tc) == 1;
}

/* Is the wedge between the curves from apex to c1 and c2 of the other sign? */
static bool wedge_at(ism_cell_ctx *cx, const ism_tile *t, const ism_fevent *apex,
                     const ism_fevent *c1, const ism_fevent *c2)
{
    double d1[3], d2[3], dir[3];
    for (int k = 0; k < 3; k++) {
        d1[k] = c1->pt.p[k] - apex->pt.p[k];
        d2[k] = c2->pt.p[k] - apex->pt.p[k];
    }
    double l1 = ism_normalise3(d1), l2 = ism_normalise3(d2);
    if (!(l1 > 0) || !(l2 > 0))
        return false;
    for (int k = 0; k < 3; k++)
        dir[k] = d1[k] + d2[k];
    if (!(ism_normalise3(dir) > WEDGE_MIN_BISECTOR))
        return false;
    double step = WEDGE_PROBE_FRAC * tile_size(cx, t);
    double lim = WEDGE_PROBE_ARM * (l1 < l2 ? l1 : l2);
    if (step > lim)
        step = lim;
    double q[3];
    for (int k = 0; k < 3; k++)
        q[k] = apex->pt.p[k] + step * dir[k];
    return ism_sign(ism_sample_f(&cx->s, q)) == -apex->before;
}

typedef struct pair {
    int a, b; /* event indices */
} pair;

/* Lines of one family: join the two crossings around each arc of sign `cut`. */
static int family(const ism_cell_ctx *cx, const int *cross, int nc, int cut, pair *out,
                  double *score)
{
    int n = 0;
    *score = 0;
    for (int i = 0; i < nc; i++) {
        const ism_fevent *e = &cx->ev[cross[i]];
        if (e->after == cut) {
            int j = cross[(i + 1) % nc];
            out[n++] = (pair){cross[i], j};
            *score += unit_dot(e->pt.g, cx->ev[j].pt.g);
        }
    }
    return n;
}

/* A point of the boundary arc that starts at crossing event a and ends at event b: a lattice
 * point between them, or, when both lie on one segment, the middle of the two. */
static const double *arc_point(const ism_cell_ctx *cx, const ism_fevent *a, const ism_fevent *b,
                               double mid[3])
{
    if (a->seg == b->seg) {
        for (int k = 0; k < 3; k++)
            mid[k] = 0.5 * (a->pt.p[k] + b->pt.p[k]);
        return mid;
    }
    return cx->bp[((size_t)a->seg + 1) % cx->nbp].p;
}

/* Do p and q lie on one side of the tile? Two points of different arcs of one sign on one
 * side have an arc of the other sign between them on that side: the straight path from one
 * to the other runs along the boundary through it, however narrow it is (a wedge between two
 * sheets pokes through a side in an arc much shorter than the path's sample spacing):
 *
 *   +----------------------+        p and q: the two − arcs' points (corners of one side)
 *   |  +      /            |        the + arc between them is the wedge's mouth, 1/40 of
 *   |        /      −      |        the side: samples along the side would miss it and
 *   |_      /              |        call the − arcs joined
 *   | \ −  / +             |
 *   p-------k0-k1-----------q
 */
static bool on_one_side(const ism_cell_ctx *cx, const ism_tile *t, const double p[3],
                        const double q[3], int *axis, double *from, double *to)
{
    const ism_grid *g = &cx->tree->grid;
    int uv[2] = {ism_axis_next(t->axis), ism_axis_prev(t->axis)};
    double s[2][2] = {{ism_grid_coord(g, uv[0], t->u0), ism_grid_coord(g, uv[0], t->u1)},
                      {ism_grid_coord(g, uv[1], t->v0), ism_grid_coord(g, uv[1], t->v1)}};
    for (int a = 0; a < 2; a++)
        for (int k = 0; k < 2; k++)
            if (p[uv[a]] == s[a][k] && q[uv[a]] == s[a][k]) {
                *axis = uv[a];
                *from = s[a][k];
                *to = s[a][1 - k];
                return true;
            }
    return false;
}

/* Does f keep the given sign at JOIN_SAMPLES points strictly between a and b? */
static bool path_keeps_sign(ism_cell_ctx *cx, const double a[3], const double b[3], int sign)
{
    for (int k = 1; k <= JOIN_SAMPLES; k++) {
        double t = (double)k / (JOIN_SAMPLES + 1), q[3];
        for (int i = 0; i < 3; i++)
            q[i] = a[i] + t * (b[i] - a[i]);
        if (ism_sign(ism_sample_f(&cx->s, q)) != sign)
            return false;
    }
    return true;
}

/* Four crossings leave two boundary arcs of each sign, and the two lines either cut off the
 * two + arcs (the − region crosses the tile and joins its arcs) or the two − arcs; the signs
 * alone cannot tell (a saddle, or a small ellipse near a corner, as where a cone's nappe pokes
 * through a node's edges). Returns true when f keeps the sign of the arcs starting at
 * cross[first] and cross[first + 2] all along the straight path between points of the two:
 * that sign's region is connected inside the tile, so the lines cut off the other sign's arcs. */
/* The straight path between the arcs starting at cross[first] and cross[first + 2]: a point
 * of each (arc_point), copied into p1 and p2. */
static void arc_path(const ism_cell_ctx *cx, const int *cross, int first, double p1[3],
                     double p2[3])
{
    const ism_fevent *e = cx->ev;
    double m1[3], m2[3];
    memcpy(p1, arc_point(cx, &e[cross[first]], &e[cross[first + 1]], m1), 3 * sizeof *p1);
    memcpy(p2, arc_point(cx, &e[cross[first + 2]], &e[cross[(first + 3) % 4]], m2),
           3 * sizeof *p2);
}

static bool arcs_joined(ism_cell_ctx *cx, const ism_tile *t, const int *cross, int first)
{
    double p1[3], p2[3], from, to;
    int axis;
    arc_path(cx, cross, first, p1, p2);
    if (on_one_side(cx, t, p1, p2, &axis, &from, &to))
        return false; /* the path is the boundary, where the other sign's arc lies between */
    return path_keeps_sign(cx, p1, p2, cx->ev[cross[first]].after);
}

/* Arcs whose points lie on one side of the tile (no straight path between them: on_one_side)
 * may still join around the other sign's arc between them — a narrow bump of the other sign
 * poking through that side:
 *
 *   +-----------------------+
 *   |           +           |   + above (the tile's centre is +)
 *   k3 ------------------- k2
 *   |    −         m        |   − joins its arcs under the + region, around the bump;
 *   |   ·····    ·   ·····  |   the path p → m → q shows it
 *   |        · /‾‾‾\ ·      |
 *   p---------k0-+-k1-------q   the bump k0–k1: + (a plate's top 0.2 cells high)
 *
 * With neither sign's straight path joined, the gradient scores tie (the bump's sides face
 * each other, the plane's crossings agree) and the centre's sign joined the + arcs: the bump
 * glued to the plane above it. The path is bent through m, the middle of p and q moved into
 * the tile by k/BENT_STEPS of its extent across that side, k = 1 .. BENT_STEPS − 1; true
 * when f keeps the arcs' sign along both legs at some k. */
static bool arcs_joined_around(ism_cell_ctx *cx, const ism_tile *t, const int *cross, int first)
{
    double p1[3], p2[3], from, to;
    int axis;
    arc_path(cx, cross, first, p1, p2);
    if (!on_one_side(cx, t, p1, p2, &axis, &from, &to))
        return false;
    int sign = cx->ev[cross[first]].after;
    for (int k = 1; k < BENT_STEPS; k++) {
        double m[3];
        for (int i = 0; i < 3; i++)
            m[i] = 0.5 * (p1[i] + p2[i]);
        m[axis] = from + (to - from) * k / BENT_STEPS;
        if (path_keeps_sign(cx, p1, m, sign) && path_keeps_sign(cx, m, p2, sign))
            return true;
    }
    return false;
}

/* Both signs' straight paths kept their sign, which two lines that do not cross allow only
 * one of: a path stepped over a band of the other sign narrower than its samples (the double
 * torus's seam 1e-3 off the lattice: a + strip 4e-4 wide crossing a tile 0.011 wide, which
 * the − diagonal stepped over; the centre's sign then cut the strip into two bumps and left
 * holes). The two paths cross inside the tile (their ends alternate around its boundary):
 * the path of the sign f does not have there runs through the other's region. Returns the
 * first pair's verdict (true: the arcs at cross[0], cross[2] join), or -1 when the paths do
 * not cross or f is 0 there. */
static int joined_where_paths_cross(ism_cell_ctx *cx, const ism_tile *t, const int *cross)
{
    int u = ism_axis_next(t->axis), v = ism_axis_prev(t->axis);
    double p1[3], p2[3], q1[3], q2[3];
    arc_path(cx, cross, 0, p1, p2);
    arc_path(cx, cross, 1, q1, q2);
    double du = p2[u] - p1[u], dv = p2[v] - p1[v], eu = q2[u] - q1[u], ev = q2[v] - q1[v];
    double den = du * ev - dv * eu;
    if (!(den != 0.0))
        return -1;
    double a = ((q1[u] - p1[u]) * ev - (q1[v] - p1[v]) * eu) / den; /* along p1 → p2 */
    double b = ((q1[u] - p1[u]) * dv - (q1[v] - p1[v]) * du) / den; /* along q1 → q2 */
    if (!(a > 0.0 && a < 1.0 && b > 0.0 && b < 1.0))
        return -1;
    double x[3];
    for (int k = 0; k < 3; k++)
        x[k] = p1[k] + a * (p2[k] - p1[k]);
    int s = ism_sign(ism_sample_f(&cx->s, x));
    return s == 0 ? -1 : s == cx->ev[cross[0]].after;
}

/* Does one of lines l[0..n) join two crossings on one side of tile t (a chord) with no arc
 * of f = 0 across the tile from its middle (ism_lift_chord finds none: f keeps the chord's
 * inner sign up to the far side)? Then the inner sign's region is no cap cut off by the chord
 * but crosses the tile, joining its two arcs: the other family's lines are the true ones. The
 * paths of arcs_joined miss such a region where it is a wedge narrower than their samples
 * near the chord: the double torus's seam (f = min of two tori, mirror images in x = 1.1),
 * box moved by (0.37, −0.23, 0.41) of a depth-8 cell, E 0.0116, where the crease passes 1e-5
 * from the lattice edge y = −1.015734375, z = 0.0525625: that edge holds two roots 1.8e-5
 * apart; the tile above it (x from 0.927 to 1.108, z to 0.1026) has them and two crossings
 * at its top right, and the wedge between the tori's sheets widens from the two roots to the
 * corner. Joined as a chord, the chord's lift ran up the mirror plane inside the wedge and
 * found nothing; the node above then held a flat triangle in its lower face (the chord and
 * the lifted line of the face below), which face_flat leaves to the face's owner — whose
 * own line on that edge was lifted, so nobody emitted it: a crack of 4 edges (χ −3, one
 * boundary loop, instead of −2 and none). */
static bool unlifted_chord(ism_cell_ctx *cx, const ism_tile *t, const pair *l, int n)
{
    for (int i = 0; i < n; i++) {
        const ism_fpoint *pa = &cx->ev[l[i].a].pt, *pb = &cx->ev[l[i].b].pt;
        double from, to;
        int axis;
        ism_fpoint mid;
        if (on_one_side(cx, t, pa->p, pb->p, &axis, &from, &to) &&
            !ism_lift_chord(&cx->s, pa, pb, axis, to, &mid))
            return true;
    }
    return false;
}

/* The subtle case, 4 crossings k0..k3 in walking order around the tile, x where the chords
 * k0-k2 and k1-k3 meet (is_crossing_x):
 *
 *   two sheets cross at x (an X):            a cone's apex just off the face:
 *   f = 0 and ∇f = 0 at x                    f(x) > 0, the face cuts a hyperbola
 *   +------k0-------k1------+                +------k0-------k1------+
 *   |       \   -   /       |                |       \   -   /       |
 *   |   +    \     /    +   |                |   +    `-----'    +   |
 *   |         \   /         |                |                       |
 *   |           x           |                |           x           |
 *   |         /   \         |                |                       |
 *   |   +    /     \    +   |                |   +    .-----.    +   |
 *   |       /   -   \       |                |       /   -   \       |
 *   +------k3-------k2------+                +------k3-------k2------+
 *   lines k0-k2 and k1-k3, through x when    lines k0-k1 and k3-k2: the branches cut
 *   it is a singular point (ISM_PLANE_APEX)  off the arcs of the sign f does NOT have
 *                                            at x; the + region joins through x
 *
 * Both look alike from the boundary (same signs, near-parallel gradients at k0, k2 and at
 * k1, k3); ism_plane_crossing tells them apart by Newton on the face's in-plane gradient.
 * Joins crossings into lines; writes them to lines[] and returns how many. When two sheets
 * cross at a singular point of the tile, the two lines are the X's and *has_apex is set with
 * the point in *apex: the lines go through it. */
static int pair_crossings(ism_cell_ctx *cx, const ism_tile *t, const int *cross, int nc,
                          pair *lines, ism_fpoint *apex, bool *has_apex)
{
    *has_apex = false;
    if (nc == 2) {
        lines[0] = (pair){cross[0], cross[1]};
        return 1;
    }
    pair fp[MAX_CROSS], fm[MAX_CROSS];
    double sp, sm;
    int np = family(cx, cross, nc, +1, fp, &sp);
    int nm = family(cx, cross, nc, -1, fm, &sm);
    double x[3];
    if (nc == 4) {
        ism_fevent *k[4] = {&cx->ev[cross[0]], &cx->ev[cross[1]], &cx->ev[cross[2]],
                            &cx->ev[cross[3]]};
        if (is_crossing_x(cx, t, k, x)) {
            int kind = tile_plane_crossing(cx, t, x, apex);
            if (kind == 1 || kind == -1) {
                /* not two lines but a hyperbola: its branches part the arcs of the other sign */
                memcpy(lines, kind > 0 ? fm : fp, (size_t)(kind > 0 ? nm : np) * sizeof *lines);
                return kind > 0 ? nm : np;
            }
            cx->walk.crossed_faces++;
            *has_apex = kind == ISM_PLANE_APEX;
            lines[0] = (pair){cross[0], cross[2]};
            lines[1] = (pair){cross[1], cross[3]};
            return 2;
        }
    }
    bool plus;
    bool joined0 = nc == 4 && arcs_joined(cx, t, cross, 0);
    bool joined1 = nc == 4 && arcs_joined(cx, t, cross, 1);
    int at_cross = joined0 && joined1 ? joined_where_paths_cross(cx, t, cross) : -1;
    if (at_cross >= 0) {
        joined0 = at_cross == 1;
        joined1 = !joined0;
    } else if (nc == 4 && !joined0 && !joined1) {
        joined0 = arcs_joined_around(cx, t, cross, 0);
        joined1 = arcs_joined_around(cx, t, cross, 1);
    }
    if (joined0 != joined1) {
        /* the region of the joined arcs' sign crosses the tile: cut off the other sign's arcs */
        int joined_sign = cx->ev[cross[joined0 ? 0 : 1]].after;
        plus = joined_sign < 0;
    } else if (fabs(sp - sm) > FAMILY_SCORE_MARGIN * np) {
        plus = sp > sm;
    } else {
        double c[3];
        tile_centre(cx, t, c);
        plus = ism_sample_f(&cx->s, c) < 0; /* centre negative: cut off the + arcs */
    }
    if (nc == 4 && unlifted_chord(cx, t, plus ? fp : fm, plus ? np : nm) &&
        !unlifted_chord(cx, t, plus ? fm : fp, plus ? nm : np))
        plus = !plus; /* see unlifted_chord */
    memcpy(lines, plus ? fp : fm, (size_t)(plus ? np : nm) * sizeof *lines);
    return plus ? np : nm;
}

static bool emit(ism_cell_ctx *cx, int a, int b, int kind)
{
    return ism_flines_push(&cx->lines, &cx->ev[a].pt, &cx->ev[b].pt, kind);
}

/* A line of one polygon; a chord along one side of the tile goes through the point of its
 * arc across the tile instead (face_flat.h: else the tile across that side may hold the
 * same chord for its own arc, and four polygons would share one edge). */
static bool emit_regular(ism_cell_ctx *cx, const ism_tile *t, int a, int b)
{
    const ism_fpoint *pa = &cx->ev[a].pt, *pb = &cx->ev[b].pt;
    double from, to;
    int axis;
    ism_fpoint mid;
    if (on_one_side(cx, t, pa->p, pb->p, &axis, &from, &to) &&
        ism_lift_chord(&cx->s, pa, pb, axis, to, &mid)) {
        cx->walk.lifted_chords++;
        return ism_flines_push(&cx->lines, pa, &mid, ISM_LINE_REGULAR) &&
               ism_flines_push(&cx->lines, &mid, pb, ISM_LINE_REGULAR);
    }
    return emit(cx, a, b, ISM_LINE_REGULAR);
}

/* Points of a tile (fractions of its sides) where a zero tile is confirmed besides its
 * centre: on no line through two of the tile's corners or side midpoints, so the lines of
 * f = 0 that run through those (Clebsch's cubic in its own box: on the plane z = −1,
 * f = −3xy(x + y), zero on two sides of a tile and on its diagonal through the centre) do
 * not pass for a plane of zeros. */
static const double ZERO_TILE_PROBES[2][2] = {{0.3090, 0.7236}, {0.6910, 0.2764}};

/* f = 0 on the whole tile: at every boundary point, at the centre and at the probes. */
static bool is_zero_tile(ism_cell_ctx *cx, const ism_tile *t)
{
    for (size_t i = 0; i < cx->nbp; i++)
        if (cx->bp[i].f != 0)
            return false;
    double c[3];
    tile_centre(cx, t, c);
    if (!(fabs(ism_sample_f(&cx->s, c)) <= cx->roots.eps))
        return false;
    const ism_grid *g = &cx->tree->grid;
    int u = ism_axis_next(t->axis), v = ism_axis_prev(t->axis);
    double u0 = ism_grid_coord(g, u, t->u0), u1 = ism_grid_coord(g, u, t->u1);
    double v0 = ism_grid_coord(g, v, t->v0), v1 = ism_grid_coord(g, v, t->v1);
    for (int k = 0; k < 2; k++) {
        c[u] = u0 + ZERO_TILE_PROBES[k][0] * (u1 - u0);
        c[v] = v0 + ZERO_TILE_PROBES[k][1] * (v1 - v0);
        if (!(fabs(ism_sample_f(&cx->s, c)) <= cx->roots.eps))
            return false;
    }
    return true;
}

/* Bisection steps for a crossing hidden in a zero run: halves the segment down to 2^-52 of
 * its length, the resolution of its coordinates. */
#define ZERO_RUN_BISECTIONS 52

/* P as the point q found on a zero run (zero_run_crossing, singular_run): f = 0 there, its
 * gradient sampled. */
static void zero_run_point(ism_cell_ctx *cx, const double q[3], ism_fpoint *P)
{
    memcpy(P->p, q, sizeof P->p);
    ism_sample_grad(&cx->s, q, P->g);
    P->flags = ISM_FP_ZERO;
}

/* A line of f = 0 that leaves a zero run of the tile's boundary into the tile (a smooth
 * surface containing a lattice line and crossing the lattice plane there: the helicoid's
 * axis on the plane x = 0, where its ruling at z = π/4 lies in the plane too):
 *
 *     A ══════════ P ══════════ B     zero run A..B on the tile's side; f just inside the
 *        +         │      −           tile has one sign near A and the other near B, so a
 *                  │                  line of f = 0 leaves the run at P, where the in-plane
 *     ─────────────E──────────────    derivative across the side changes sign, and meets
 *                                     the crossing E (otherwise without a partner)
 *
 * Finds the first zero run ev[i] → ev[i + 1] whose ends' derivatives across it (the
 * gradient's in-plane component perpendicular to the run) have opposite signs, and P on it
 * by bisection over the run's canonical direction (increasing coordinate), so both tiles
 * sharing the run find the same P bit for bit. Returns i, or -1. */
static int zero_run_crossing(ism_cell_ctx *cx, const ism_tile *t, ism_fpoint *P)
{
    int u = ism_axis_next(t->axis), v = ism_axis_prev(t->axis), ne = (int)cx->nev;
    for (int i = 0; i < ne; i++) {
        const ism_fevent *a = &cx->ev[i], *b = &cx->ev[(i + 1) % ne];
        if (a->after != 0 || b->before != 0 || a == b)
            continue;
        int along = a->pt.p[u] != b->pt.p[u] ? u : v, perp = along == u ? v : u;
        if (a->pt.p[perp] != b->pt.p[perp] || !(a->pt.g[perp] * b->pt.g[perp] < 0))
            continue;
        bool up = a->pt.p[along] < b->pt.p[along];
        const ism_fevent *lo = up ? a : b, *hi = up ? b : a;
        double x0 = lo->pt.p[along], x1 = hi->pt.p[along], s0 = lo->pt.g[perp];
        double q[3] = {lo->pt.p[0], lo->pt.p[1], lo->pt.p[2]}, g[3];
        for (int k = 0; k < ZERO_RUN_BISECTIONS && x1 - x0 > 0; k++) {
            q[along] = 0.5 * (x0 + x1);
            ism_sample_grad(&cx->s, q, g);
            if ((g[perp] < 0) == (s0 < 0))
                x0 = q[along];
            else
                x1 = q[along];
        }
        q[along] = 0.5 * (x0 + x1);
        if (!(q[along] > lo->pt.p[along] && q[along] < hi->pt.p[along]))
            continue;
        zero_run_point(cx, q, P);
        return i;
    }
    return -1;
}

/* A surface tangent to the tile's plane at a lattice point that ends a zero run has f's
 * in-plane gradient below this fraction of |∇f| there (rounding of an exact 0). */
#define TANGENT_PLANE_REL 1e-9

/* The end of a zero run (or a corner between two) where a line of f = 0 leaves it: the
 * run's lattice line and a second line of the surface cross there, and the surface is
 * tangent to the tile's plane (Clebsch's cubic in its own box: the lines z = −1 and
 * x + z = 0 of the plane y = 0 meet at (1, 0, −1), the second one running through the
 * tiles' corners; at (0, 0, −1) three lines of the plane z = −1 meet, two of them lattice
 * lines). Returns its event index, or -1. */
static int zero_run_tangent_end(const ism_cell_ctx *cx, const ism_tile *t)
{
    int u = ism_axis_next(t->axis), v = ism_axis_prev(t->axis);
    for (int i = 0; i < (int)cx->nev; i++) {
        const ism_fevent *e = &cx->ev[i];
        if (!(e->pt.flags & ISM_FP_ZERO) || (e->before != 0 && e->after != 0))
            continue;
        double g = ism_norm3(e->pt.g);
        if (g > 0 && fabs(e->pt.g[u]) <= TANGENT_PLANE_REL * g &&
            fabs(e->pt.g[v]) <= TANGENT_PLANE_REL * g)
            return i;
    }
    return -1;
}

/* Probes beside a zero run (singular_run): this fraction of the run's length off it
 * (beside_signs), or of the tile's extent across the run into the tile (the end rule) — near
 * enough to see the sign f keeps beside the run, far enough for f there (second order in
 * the offset where the run is singular: 4x²(z² + z) beside the cross-cap's axis) to stand
 * above the root finder's eps. */
#define SINGULAR_RUN_PROBE_FRAC 0.05
/* The search for where f's signs beside a singular run change starts this fraction of the
 * run inside either end (beside an end, which is itself singular, the signs are its own). */
#define SINGULAR_RUN_END_GAP (1.0 / 1024)

/* The signs of f beside the run's lattice line at coordinate x along it, off by ±d across
 * both other axes, as 8 bits (2 per probe: f < -eps, f > eps); the same for every tile that
 * holds the run. */
static unsigned beside_signs(ism_cell_ctx *cx, const double on[3], int along, double x, double d)
{
    unsigned code = 0;
    for (int k = 1; k <= 2; k++)
        for (int sgn = -1; sgn <= 1; sgn += 2) {
            double q[3] = {on[0], on[1], on[2]};
            q[along] = x;
            q[(along + k) % 3] += sgn * d;
            double f = ism_sample_f(&cx->s, q);
            code = code << 2 | (unsigned)(f < -cx->roots.eps) | (unsigned)(f > cx->roots.eps) << 1;
        }
    return code;
}

/* A zero run along which ∇f vanishes (a singular lattice line: the cross-cap's z axis in its
 * own box) that the tile's one crossing E leaves for (the boundary's signs before the run's
 * start A and after its end B differ). ∇f = 0 there (at A and B under TANGENT_PLANE_REL of
 * |∇f| at E), so zero_run_crossing's derivative test and zero_run_tangent_end's tangency
 * test see nothing. The line meets the run where f's sign beside it changes:
 *
 *   - inside the run: the signs beside the run (beside_signs, every tile holding the run
 *     the same samples) differ near its two ends; P by bisection over the run's canonical
 *     direction, so all its tiles find the same P bit for bit. Face x = 0 of the cell
 *     y in [-h, 0], z in [0.994, 1.013]: f = y²(y² + z² − 1), the circle y² + z² = 1 leaves
 *     the axis at the pinch point P = (0, 0, 1);
 *   - else at one end, the one whose outer sign differs from f beside the run in the tile
 *     (three probes, one sign):
 *
 *     A ═══════════════ B ++++++     face y = 0 of the cell x, y in [0, h], z in [-h, 0],
 *     −    f < 0 beside    \         B the pinch point 0: f = 4x²(x² + z² + z) is 0 on the
 *     −    the run          E        axis A..B, negative beside it, positive on the side
 *                                    z = 0 after B: the circle x² + (z + ½)² = ¼ joins E to B
 *
 * Returns the run's first event index (its `after` is 0) with *end = -1 and *P set (inside),
 * or with *end the end's event index; -1 when no run qualifies. */
static int singular_run(ism_cell_ctx *cx, const ism_tile *t, double gcross, int *end,
                        ism_fpoint *P)
{
    const ism_grid *g = &cx->tree->grid;
    double gzero = TANGENT_PLANE_REL * gcross; /* ∇f "vanishes": rounding of an exact 0 */
    int u = ism_axis_next(t->axis), v = ism_axis_prev(t->axis), ne = (int)cx->nev;
    *end = -1;
    for (int i = 0; i < ne; i++) {
        int j = (i + 1) % ne;
        const ism_fevent *a = &cx->ev[i], *b = &cx->ev[j];
        if (a == b || a->after != 0 || b->before != 0 || a->before == 0 || b->after == 0 ||
            a->before == b->after || !(ism_norm3(a->pt.g) <= gzero) ||
            !(ism_norm3(b->pt.g) <= gzero))
            continue;
        int along = a->pt.p[u] != b->pt.p[u] ? u : v, perp = along == u ? v : u;
        if (a->pt.p[perp] != b->pt.p[perp])
            continue;
        bool up = a->pt.p[along] < b->pt.p[along];
        const ism_fevent *lo = up ? a : b, *hi = up ? b : a;
        double x0 = lo->pt.p[along], x1 = hi->pt.p[along], len = x1 - x0;
        double d = SINGULAR_RUN_PROBE_FRAC * len;
        double s0 = x0 + SINGULAR_RUN_END_GAP * len, s1 = x1 - SINGULAR_RUN_END_GAP * len;
        unsigned c0 = beside_signs(cx, lo->pt.p, along, s0, d);
        if (beside_signs(cx, lo->pt.p, along, s1, d) != c0) {
            for (int k = 0; k < ZERO_RUN_BISECTIONS && s1 - s0 > 0; k++) {
                double m = 0.5 * (s0 + s1);
                if (m <= s0 || m >= s1)
                    break;
                if (beside_signs(cx, lo->pt.p, along, m, d) == c0)
                    s0 = m;
                else
                    s1 = m;
            }
            double q[3] = {lo->pt.p[0], lo->pt.p[1], lo->pt.p[2]};
            q[along] = 0.5 * (s0 + s1);
            zero_run_point(cx, q, P);
            return i;
        }
        /* one sign beside the run: the line leaves at the end whose outer sign differs */
        int32_t plo = perp == u ? t->u0 : t->v0, phi = perp == u ? t->u1 : t->v1;
        double c0p = ism_grid_coord(g, perp, plo), c1p = ism_grid_coord(g, perp, phi);
        double inward = a->pt.p[perp] == c0p ? c1p - c0p : c0p - c1p;
        int sign = 0;
        bool agree = true;
        for (int k = 1; k <= 3 && agree; k++) {
            double q[3] = {a->pt.p[0], a->pt.p[1], a->pt.p[2]};
            q[along] += 0.25 * k * (b->pt.p[along] - a->pt.p[along]);
            q[perp] += SINGULAR_RUN_PROBE_FRAC * inward;
            double f = ism_sample_f(&cx->s, q);
            int sg = fabs(f) <= cx->roots.eps ? 0 : ism_sign(f);
            agree = sg != 0 && (sign == 0 || sg == sign);
            sign = sg;
        }
        if (!agree)
            continue;
        if (sign == a->before || sign == b->after) {
            *end = sign == a->before ? j : i; /* f keeps A's outer sign beside: leaves at B */
            return i;
        }
    }
    return -1;
}

static ism_quiet_tile *quiet_slot(ism_cell_ctx *cx, uint64_t hash)
{
    return &cx->cache.quiet[hash & (((uint64_t)1 << ISM_QUIET_CACHE_BITS) - 1)];
}

static ism_tile_memo *memo_slot(ism_cell_ctx *cx, uint64_t hash)
{
    return &cx->cache.tiles[hash & (((uint64_t)1 << ISM_TILE_MEMO_BITS) - 1)];
}

void ism_lattice_prefetch(ism_cell_ctx *cx, const int32_t ip[3])
{
    uint64_t h = ism_cache_mix(ism_lattice_key(ip));
    __builtin_prefetch(lattice_slot(cx, h), 1);
    __builtin_prefetch(ism_breaks_slot(cx->breaks, h));
}

void ism_tile_prefetch(ism_cell_ctx *cx, const ism_node_tile *nt, bool corners)
{
    __builtin_prefetch(quiet_slot(cx, nt->hash), 0);
    __builtin_prefetch(memo_slot(cx, nt->hash), 0);
    if (!corners)
        return;
    int32_t q[4][3];
    ism_tile_corners(&nt->t, q);
    for (int c = 0; c < 4; c++)
        ism_lattice_prefetch(cx, q[c]);
}

/* Adds counts c to the thread's counters. */
static void add_counts(ism_cell_ctx *cx, const ism_tile_counts *c)
{
    cx->stats.crossed_faces += c->crossed_faces;
    cx->stats.lifted_chords += c->lifted_chords;
    cx->stats.open_chains += c->open_chains;
    cx->stats.singular_points += c->singular_points;
    cx->stats.double_lines += c->double_lines;
}

/* The walk's lines (cx->lines from `first`) and counts (cx->walk) into memo entry m, when
 * they fit; else m is left as it was. */
static void remember(ism_cell_ctx *cx, ism_tile_memo *m, const ism_quiet_tile *key,
                     size_t first)
{
    size_t n = cx->lines.n - first;
    if (n > ISM_TILE_MEMO_LINES)
        return;
    m->counted = cx->walk;
    if (n) /* a walk may add no line, and cx->lines.v is NULL until a first line is pushed */
        memcpy(m->lines, &cx->lines.v[first], n * sizeof *m->lines);
    m->nlines = n;
    m->key = *key;
}

/* The tile's first walk again: its lines appended, then its counts added (none when a push
 * runs out of memory, so the counters never count lines that were not appended). */
static bool replay(ism_cell_ctx *cx, const ism_tile_memo *m)
{
    for (size_t l = 0; l < m->nlines; l++)
        if (!ism_flines_push(&cx->lines, &m->lines[l].a, &m->lines[l].b, m->lines[l].kind))
            return false;
    add_counts(cx, &m->counted);
    return true;
}

/* Under walk_every_tile, quiet_by_corners' answer for the tile just walked (by_corners)
 * checked against the walk, tile by tile: the shortcut holds exactly for a walk that collected
 * the four corners alone, found every side rootless (no segment looked at: tile_events left
 * that in cx->gap: no segment slot) and no event, and was no zero tile. Counted in
 * corner_checks (tiles quiet by their corners, walked all the same) and corner_mismatches
 * (answers that differ: none where f is finite; a corner where f is not may make a tile
 * whose sides are all rootless span both signs, which the shortcut leaves to the walk). Out
 * of line: only the tests' reference (walk_every_tile) calls it. */
static __attribute__((noinline, cold)) void check_by_corners(ism_cell_ctx *cx, bool by_corners,
                                                             bool zero)
{
    bool idle = !zero && cx->nbp == 4 && cx->nev == 0;
    for (size_t i = 0; idle && i < 4; i++)
        idle = !cx->gap[i].seg;
    cx->corner_checks += by_corners;
    cx->corner_mismatches += by_corners != idle;
}

/* ism_tile_lines's walk of a tile neither memo holds (q: its quiet-tile slot); what it
 * counts goes to cx->walk (counted_walk adds it to the thread's counters). */
static bool walk_tile(ism_cell_ctx *cx, const ism_tile *t, const ism_quiet_tile *key,
                      ism_quiet_tile *q)
{
    bool quiet;
    if (!tile_boundary(cx, t, &quiet))
        return false;
    if (quiet && !cx->walk_every_tile) {
        cx->corner_quiets++;
        cx->nev = 0;
        *q = *key;
        return true;
    }
    if (is_zero_tile(cx, t)) {
        if (cx->walk_every_tile)
            check_by_corners(cx, quiet, true);
        cx->zero_tile = true;
        return true;
    }
    if (!tile_events(cx))
        return false;
    if (cx->walk_every_tile)
        check_by_corners(cx, quiet, false);
    if (cx->nev == 0) { /* nothing crosses the tile's boundary (most tiles): no lines */
        *q = *key;
        return true;
    }
    int ne = (int)cx->nev;
    int cross[MAX_CROSS], touch[MAX_CROSS], nc = 0, nt = 0;
    for (int i = 0; i < ne; i++) {
        ism_fevent *e = &cx->ev[i];
        if ((e->before == 0 || e->after == 0) || e->before == e->after)
            continue;
        nc++;
    }
    ism_fpoint hidden;
    int hidden_run = nc % 2 == 1 ? zero_run_crossing(cx, t, &hidden) : -1;
    int singular_end = -1;
    if (nc == 1 && hidden_run < 0) { /* ... or leaves a singular run (∇f = 0 along it) */
        double gcross = 0;
        for (int i = 0; i < ne; i++) {
            const ism_fevent *e = &cx->ev[i];
            if (e->before != 0 && e->after != 0 && e->before != e->after)
                gcross = ism_norm3(e->pt.g);
        }
        int run = singular_run(cx, t, gcross, &singular_end, &hidden);
        if (run >= 0 && singular_end < 0)
            hidden_run = run;
    }
    nc = 0;
    for (int i = 0; i < ne; i++) {
        ism_fevent *e = &cx->ev[i];
        if (e->before == 0 || e->after == 0) {
            /* a zero run: the segment after this event lies in f = 0 (split where a line
             * leaves it) */
            if (e->after == 0 && i == hidden_run) {
                const ism_fpoint *b = &cx->ev[(i + 1) % ne].pt;
                if (!ism_flines_push(&cx->lines, &e->pt, &hidden, ISM_LINE_EDGE) ||
                    !ism_flines_push(&cx->lines, &hidden, b, ISM_LINE_EDGE))
                    return false;
            } else if (e->after == 0 && !emit(cx, i, (i + 1) % ne, ISM_LINE_EDGE)) {
                return false;
            }
        } else if (e->before != e->after) {
            if (nc < MAX_CROSS)
                cross[nc++] = i;
        } else if (nt < MAX_CROSS) {
            touch[nt++] = i;
        }
    }
    if (nc == 1 && hidden_run >= 0) { /* the crossing's partner left the zero run */
        if (!ism_flines_push(&cx->lines, &hidden, &cx->ev[cross[0]].pt, ISM_LINE_REGULAR))
            return false;
        nc = 0;
    }
    int end = nc == 1 ? zero_run_tangent_end(cx, t) : -1;
    if (nc == 1 && end < 0)
        end = singular_end;
    if (end >= 0) { /* ... or left it at its end */
        if (!emit(cx, end, cross[0], ISM_LINE_REGULAR))
            return false;
        nc = 0;
    }
    if (nc % 2 == 1) {
        cx->walk.open_chains++; /* inconsistent signs: drop the last crossing */
        nc--;
    }
    pair lines[MAX_CROSS];
    ism_fpoint apex;
    bool has_apex = false;
    int nl = nc ? pair_crossings(cx, t, cross, nc, lines, &apex, &has_apex) : 0;
    bool line_used[MAX_CROSS] = {false};
    if (has_apex) {
        /* the two sheets cross at a singular point of the face: all four lines meet there */
        cx->walk.singular_points++;
        for (int l = 0; l < 2; l++) {
            line_used[l] = true;
            if (!ism_flines_push(&cx->lines, &cx->ev[lines[l].a].pt, &apex, ISM_LINE_REGULAR) ||
                !ism_flines_push(&cx->lines, &apex, &cx->ev[lines[l].b].pt, ISM_LINE_REGULAR))
                return false;
        }
    }

    /* tangent roots: double lines between pairs of them, else wedge apexes */
    bool touch_used[MAX_CROSS] = {false};
    for (int i = 0; i < nt; i++) {
        for (int j = i + 1; j < nt && !touch_used[i]; j++) {
            if (touch_used[j])
                continue;
            if (double_line_between(cx, t, &cx->ev[touch[i]].pt, &cx->ev[touch[j]].pt)) {
                touch_used[i] = touch_used[j] = true;
                cx->walk.double_lines++;
                if (!emit(cx, touch[i], touch[j], ISM_LINE_DOUBLE) ||
                    !emit(cx, touch[i], touch[j], ISM_LINE_DOUBLE))
                    return false;
            }
        }
    }
    for (int i = 0; i < nt; i++) {
        if (touch_used[i])
            continue;
        const ism_fevent *apex = &cx->ev[touch[i]];
        for (int l = 0; l < nl; l++) {
            if (line_used[l])
                continue;
            int a = lines[l].a, b = lines[l].b;
            /* the apex must sit on the arc between the line's two crossings */
            int lo = a < b ? a : b, hi = a < b ? b : a;
            bool inside = touch[i] > lo && touch[i] < hi;
            bool between = true;
            for (int c = 0; c < nc; c++) {
                bool cin = cross[c] > lo && cross[c] < hi;
                if (cin == inside && cross[c] != a && cross[c] != b)
                    between = false;
            }
            if (!between || !wedge_at(cx, t, apex, &cx->ev[a], &cx->ev[b]))
                continue;
            line_used[l] = true;
            touch_used[i] = true;
            if (!emit(cx, touch[i], a, ISM_LINE_REGULAR) ||
                !emit(cx, touch[i], b, ISM_LINE_REGULAR))
                return false;
            break;
        }
    }
    for (int l = 0; l < nl; l++)
        if (!line_used[l] && !emit_regular(cx, t, lines[l].a, lines[l].b))
            return false;
    return true;
}

/* walk_tile with its counts (cx->walk, from zero) added to the thread's counters, whatever
 * it answers (as when it counted there directly). */
static bool counted_walk(ism_cell_ctx *cx, const ism_tile *t, const ism_quiet_tile *key,
                         ism_quiet_tile *q)
{
    cx->walk = (ism_tile_counts){0, 0, 0, 0, 0};
    bool ok = walk_tile(cx, t, key, q);
    add_counts(cx, &cx->walk);
    return ok;
}

bool ism_tile_lines(ism_cell_ctx *cx, const ism_node_tile *nt)
{
    cx->zero_tile = false;
    const ism_tile *t = &nt->t;
    const ism_quiet_tile *key = &nt->key;
    ism_quiet_tile unused;
    if (cx->walk_every_tile)
        return counted_walk(cx, t, key, &unused);
    ism_quiet_tile *q = quiet_slot(cx, nt->hash);
    if (q->where == key->where && q->span == key->span) {
        cx->quiet_skips++;
        return true; /* walked before: nothing crosses its boundary */
    }
    ism_tile_memo *m = memo_slot(cx, nt->hash);
    if (m->key.where == key->where && m->key.span == key->span) {
        cx->tile_replays++;
        return replay(cx, m); /* walked before: lines cross it */
    }
    size_t first = cx->lines.n;
    if (!counted_walk(cx, t, key, q))
        return false;
    if (!cx->zero_tile && cx->nev > 0)
        remember(cx, m, key, first);
    return true;
}
