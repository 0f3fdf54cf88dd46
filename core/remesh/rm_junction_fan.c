/* rm_junction_fan.c — a junction's fan that misses one of its creases (rm_junction_fan_mend,
 * after the junction collapses). Where three smooth pieces of f meet at a point (three
 * balls' triple points), the polygoniser may leave the point's vertex J with a crowd vertex
 * c on one crease a hair from it and no vertex at all on a second crease nearby: J's fan then
 * holds needles J–c–w that no single step mends (three-balls, depth.max 5, 1e-3 box: the
 * upper triple point's 1.02° and 0.86°, c on the 0=2 crease 0.0019 from J, its next crease
 * vertex 0.12 out, no vertex of J's 2-ring on the 0=1 crease; sliding c alone bridges the
 * 0=1 valley, centroids 3.3 E off — crowd28.md). One operation mends it, measured as a
 * whole: the vertex x across c–w from J, free and beside the crease of the third piece, goes
 * onto that crease; c slides out along its own crease (both read by f's pieces, not by the
 * top min/max, whose crease beside a junction is two creases meeting); the edge c–w flips
 * to J–x, the missing crease's first edge. The operation stands only when J's smallest
 * angle grows, no triangle about J, c, w and x ends thinner than the thinnest there before
 * nor more of them under 10°, every triangle it changes faces its own piece's ∇f, and its
 * new centroids and midpoints keep the collapses' distance rule (rm_distances_ok); otherwise
 * it is undone: places, normals, triangles and slots as they were, bit for bit; the caches
 * of what they measure (the two triangles' centroid bounds, the moved fans' shapes) are
 * dropped, to be measured again when asked. */
#include "core/remesh/rm_cbound.h"
#include "core/remesh/rm_pass.h"
#include "core/util/vec3.h"

#include <math.h>
#include <string.h>

/* A piece vanishes at a vertex when |value| / |∇| is within this × the junction's fan's mean
 * edge: the polygoniser's junction and crease points lie on their surfaces to rounding
 * (three-balls: ~1e-9 of an edge), its edge roots beside a crease 1e-5 of an edge and more
 * off. This reads which pieces a vertex the polygoniser placed lies on; where this file
 * places a vertex (Newton onto two pieces) it lands by ISM_RM_CREASE_ON_REL, the crease
 * slides' own test, so that they read it as on its crease. */
#define ISM_RM_JFAN_ON_REL 1e-6
/* Where c slides to: this share of the way from J to its next vertex on the crease, tried in
 * this order, the best kept (crowd28's check against the balls' exact geometry: at 1/4 every
 * triangle about the point ≥ 15.7°, at 1/2 a needle of 8.81° at c's other side). */
static const double slide_share[] = {0.25, 0.375, 0.125};
#define ISM_RM_JFAN_SHARES (sizeof slide_share / sizeof *slide_share)
/* x is snapped only when the crease lies within this share of its distance from J (x goes
 * onto the missing crease beside it, not onto a crease point of some other vertex's). */
#define ISM_RM_JFAN_SNAP_REACH 0.5
/* At most this many triangles about J, c, w and x (four fans of at most
 * ISM_RM_COLLAPSE_MAX_DEGREE). */
#define ISM_RM_JFAN_REGION (4 * ISM_RM_COLLAPSE_MAX_DEGREE)

/* The three pieces meeting at J, the tolerance they are read with, and J's mean edge. */
typedef struct jf_pieces {
    ism_piece pc[3];
    double tol;       /* ISM_RM_JFAN_ON_REL × J's mean edge */
    double mean_edge; /* J's fan's */
} jf_pieces;

/* Piece pc's |value| / |∇| at x (INFINITY where ∇ vanishes or nothing is finite). */
static double piece_off(rm_pass *p, ism_piece pc, const double *x)
{
    double g[3], v = ism_eval_piece_gradient(p->f, p->ws, pc, x[0], x[1], x[2], g);
    double n = ism_norm3(g), d = fabs(v) / n;
    return n > 0 && isfinite(d) ? d : INFINITY;
}

/* The triangles of v's fan and of its neighbours' fans: their centroids' pieces, those
 * vanishing at v, into s; true when exactly three do. */
static bool pieces_at(rm_pass *p, uint32_t v, double mean_edge, jf_pieces *s)
{
    const rm_mesh *r = &p->r;
    int n = 0;
    s->tol = ISM_RM_JFAN_ON_REL * mean_edge;
    s->mean_edge = mean_edge;
    for (uint32_t i = 0; i < r->count[v]; i++) {
        const uint32_t *t = r->m->tri + 3 * (size_t)rm_slot(r, v, i);
        for (int k = 0; k < 3; k++)
            for (uint32_t j = 0; j < r->count[t[k]]; j++) {
                const uint32_t *u = r->m->tri + 3 * (size_t)rm_slot(r, t[k], j);
                double m[3];
                for (int a = 0; a < 3; a++)
                    m[a] = (rm_pos(p, u[0])[a] + rm_pos(p, u[1])[a] + rm_pos(p, u[2])[a]) / 3;
                ism_piece pc = ism_eval_piece(p->f, p->ws, m[0], m[1], m[2]);
                if (pc == ISM_PIECE_NONE)
                    return false;
                bool have = false;
                for (int h = 0; h < n && !have; h++)
                    have = s->pc[h] == pc;
                if (have || !(piece_off(p, pc, rm_pos(p, v)) <= s->tol))
                    continue;
                if (n == 3)
                    return false; /* four or more: no triple point */
                s->pc[n++] = pc;
            }
    }
    return n == 3;
}

/* Bit h set for each of s's pieces vanishing at x. */
static int vanishing(rm_pass *p, const jf_pieces *s, const double *x)
{
    int bits = 0;
    for (int h = 0; h < 3; h++)
        bits |= (piece_off(p, s->pc[h], x) <= s->tol) << h;
    return bits;
}

/* Two of f's pieces, for rm_newton_two. */
typedef struct piece_pair {
    rm_pass *p;
    ism_piece pc[2];
} piece_pair;

static bool pieces_of(void *ctx, const double x[3], double val[2], double g[2][3])
{
    const piece_pair *c = ctx;
    for (int k = 0; k < 2; k++)
        val[k] = ism_eval_piece_gradient(c->p->f, c->p->ws, c->pc[k], x[0], x[1], x[2], g[k]);
    return true;
}

/* Newton from x onto the common zero of pieces a and b, to within ISM_RM_CREASE_ON_REL ×
 * J's mean edge of both and one step more (rm_crease_slide.c's to_crease: from within that
 * it lands at rounding); g gets ∇f there. False when it does not get there, or f itself does
 * not vanish there: past J the two pieces' common curve runs inside the third piece's solid,
 * where f is the third piece's value, not 0. */
static bool onto_pair(rm_pass *p, const jf_pieces *s, ism_piece a, ism_piece b, double x[3],
                      double g[3])
{
    double tol = ISM_RM_CREASE_ON_REL * s->mean_edge, gr[2][3];
    piece_pair c = {p, {a, b}};
    if (!rm_newton_two(pieces_of, &c, x, tol, gr))
        return false;
    double v = ism_eval_gradient(p->f, p->ws, x[0], x[1], x[2], g), gn = ism_norm3(g);
    return gn > p->gthresh && fabs(v) <= tol * gn;
}

/* One try: J's needle J–c–w, c on the crease of pieces ab (bits), its next crease vertex
 * far, x across c–w from J (the flip's quad: t1 holds J, t2 holds x). */
typedef struct jf_try {
    uint32_t J, c, w, x, far, t1, t2;
    int ab; /* bits of c's two pieces in jf_pieces */
} jf_try;

/* What the operation changes, to undo it: c's and x's places and normals, the flip's
 * triangles and the slots of c and w (a slot removed takes the last one's place). */
typedef struct jf_saved {
    double pos[2][3], normal[2][3];
    float mnormal[2][3];
    uint32_t t1[3], t2[3];
    uint32_t slots[2][ISM_RM_COLLAPSE_MAX_DEGREE], count[2];
} jf_saved;

static void save_vertex(const rm_pass *p, uint32_t v, jf_saved *s, int i)
{
    memcpy(s->pos[i], rm_pos(p, v), sizeof s->pos[i]);
    memcpy(s->normal[i], p->normal + 3 * (size_t)v, sizeof s->normal[i]);
    memcpy(s->mnormal[i], p->r.m->normal + 3 * (size_t)v, sizeof s->mnormal[i]);
}

/* v (saved at i) back where it was, with its normals; the caller says it moved. */
static void restore_vertex(rm_pass *p, uint32_t v, const jf_saved *s, int i)
{
    rm_commit_move(p, v, s->pos[i], s->normal[i]);
    memcpy(p->normal + 3 * (size_t)v, s->normal[i], sizeof s->normal[i]);
    memcpy(p->r.m->normal + 3 * (size_t)v, s->mnormal[i], sizeof s->mnormal[i]);
}

/* Triangle t's corners set to c (incidence and what the pass keeps of its shape). */
static void set_corners(rm_pass *p, uint32_t t, const uint32_t c[3])
{
    double none[3] = {NAN, NAN, NAN};
    memcpy(p->r.m->tri + 3 * (size_t)t, c, 3 * sizeof *c);
    rm_shape_changed(p, t);
    rm_cbound_set(p, t, none, INFINITY, 0);
}

/* Edge c–w of triangles t1 = (c, w, J) and t2 = (w, c, x) becomes J–x: (c, x, J), (w, J, x)
 * (rm_flip.c's do_flip; winding kept). The caller reserved a slot at J and x. */
static void flip(rm_pass *p, const jf_try *q)
{
    uint32_t a[3] = {q->c, q->x, q->J}, b[3] = {q->w, q->J, q->x};
    set_corners(p, q->t1, a);
    set_corners(p, q->t2, b);
    rm_slot_remove(&p->r, q->c, q->t2);
    rm_slot_remove(&p->r, q->w, q->t1);
    rm_slot_add(&p->r, q->J, q->t2);
    rm_slot_add(&p->r, q->x, q->t1);
}

/* c's and w's slots (at most ISM_RM_COLLAPSE_MAX_DEGREE each: crowd_try) into s. */
static void save_slots(const rm_pass *p, const jf_try *q, jf_saved *s)
{
    const uint32_t v[2] = {q->c, q->w};
    for (int i = 0; i < 2; i++) {
        s->count[i] = p->r.count[v[i]];
        memcpy(s->slots[i], p->r.vt + p->r.start[v[i]], s->count[i] * sizeof *s->slots[i]);
    }
}

/* The flip undone: J's and x's slots lose their last (the flip's), c's and w's are as saved. */
static void unflip(rm_pass *p, const jf_try *q, const jf_saved *s)
{
    const uint32_t v[2] = {q->c, q->w};
    rm_slot_remove(&p->r, q->J, q->t2);
    rm_slot_remove(&p->r, q->x, q->t1);
    for (int i = 0; i < 2; i++) {
        p->r.count[v[i]] = s->count[i];
        memcpy(p->r.vt + p->r.start[v[i]], s->slots[i], s->count[i] * sizeof *s->slots[i]);
    }
    set_corners(p, q->t1, s->t1);
    set_corners(p, q->t2, s->t2);
}

/* The triangles about J, c, w and x (their fans now) into reg; false when more than
 * ISM_RM_JFAN_REGION. */
static bool region(const rm_pass *p, const jf_try *q, uint32_t *reg, int *n)
{
    const uint32_t v[4] = {q->J, q->c, q->w, q->x};
    *n = 0;
    for (int k = 0; k < 4; k++)
        for (uint32_t i = 0; i < p->r.count[v[k]]; i++) {
            uint32_t t = rm_slot(&p->r, v[k], i);
            bool have = false;
            for (int h = 0; h < *n && !have; h++)
                have = reg[h] == t;
            if (have)
                continue;
            if (*n == ISM_RM_JFAN_REGION)
                return false;
            reg[(*n)++] = t;
        }
    return true;
}

/* What the goals read of the region: its smallest sine, its needles under 10°, J's
 * smallest sine, and the farthest centroid / midpoint from f = 0 of the triangles with a
 * corner at c or x or a side on the flip (the ones the operation changes). */
typedef struct jf_measure {
    double least, at_j, far_c, far_m;
    int needles;
} jf_measure;

static bool changed(const jf_try *q, uint32_t t, const uint32_t *c)
{
    for (int k = 0; k < 3; k++)
        if (c[k] == q->c || c[k] == q->x)
            return true;
    return t == q->t1 || t == q->t2;
}

static void measure(rm_pass *p, const jf_try *q, const uint32_t *reg, int n, jf_measure *m)
{
    *m = (jf_measure){.least = INFINITY, .at_j = INFINITY};
    for (int i = 0; i < n; i++) {
        const uint32_t *c = p->r.m->tri + 3 * (size_t)reg[i];
        double s = rm_tri_sine(p, reg[i]);
        m->least = fmin(m->least, s);
        m->needles += s < rm_insert_poor();
        if (c[0] == q->J || c[1] == q->J || c[2] == q->J)
            m->at_j = fmin(m->at_j, s);
        if (!changed(q, reg[i], c))
            continue;
        const double *x[3] = {rm_pos(p, c[0]), rm_pos(p, c[1]), rm_pos(p, c[2])};
        m->far_c = fmax(m->far_c, rm_centroid_distance(p, x[0], x[1], x[2]));
        for (int k = 0; k < 3; k++)
            m->far_m = fmax(m->far_m, rm_midpoint_distance(p, x[k], x[(k + 1) % 3]));
    }
}

/* Every changed triangle of the region faces within ISM_RM_CREASE_FACE_DEG of its own
 * piece's ∇f at its centroid (the piece f takes there: beside a junction each triangle lies
 * on one of the three surfaces, and one folded over faces away from it). */
static bool facing_ok(rm_pass *p, const jf_try *q, const uint32_t *reg, int n)
{
    double turn = cos(ISM_RM_CREASE_FACE_DEG * M_PI / 180);
    for (int i = 0; i < n; i++) {
        const uint32_t *c = p->r.m->tri + 3 * (size_t)reg[i];
        if (!changed(q, reg[i], c))
            continue;
        const double *x[3] = {rm_pos(p, c[0]), rm_pos(p, c[1]), rm_pos(p, c[2])};
        double nrm[3], g[3], m[3];
        double ln = rm_cross(x[0], x[1], x[2], nrm);
        for (int k = 0; k < 3; k++)
            m[k] = (x[0][k] + x[1][k] + x[2][k]) / 3;
        ism_piece pc = ism_eval_piece(p->f, p->ws, m[0], m[1], m[2]);
        ism_eval_piece_gradient(p->f, p->ws, pc, m[0], m[1], m[2], g);
        if (!(rm_cos_bend(nrm, ln, g, ism_norm3(g)) > turn))
            return false;
    }
    return true;
}

/* Puts q's c at cx and x at xx (∇f there cg, xg; xx NULL: x stays) and flips c–w to J–x;
 * the region's figures after into *after. True when the operation passes (the file's top
 * comment); it is kept when it passes and keep is set, otherwise undone. */
static bool trial(rm_pass *p, const jf_try *q, const double cx[3], const double cg[3],
                  const double *xx, const double *xg, const jf_measure *before,
                  jf_measure *after, bool keep)
{
    uint32_t reg[ISM_RM_JFAN_REGION];
    int n;
    jf_saved s;
    if (!region(p, q, reg, &n))
        return false;
    save_vertex(p, q->c, &s, 0);
    save_vertex(p, q->x, &s, 1);
    memcpy(s.t1, p->r.m->tri + 3 * (size_t)q->t1, sizeof s.t1);
    memcpy(s.t2, p->r.m->tri + 3 * (size_t)q->t2, sizeof s.t2);
    save_slots(p, q, &s);
    rm_cbound_drop(p);
    rm_commit_move(p, q->c, cx, cg);
    if (xx)
        rm_commit_move(p, q->x, xx, xg);
    flip(p, q);
    measure(p, q, reg, n, after);
    /* J's angle must grow (progress); the region's least only not shrink: an untouched
       needle elsewhere in the region (at w or x) holds the least and must not block J */
    bool pass = after->at_j > before->at_j && after->least >= before->least &&
                after->needles <= before->needles && facing_ok(p, q, reg, n) &&
                rm_distances_ok(p, after->far_c, after->far_m, before->far_c, before->far_m);
    if (pass && keep)
        return true;
    unflip(p, q, &s);
    if (xx)
        restore_vertex(p, q->x, &s, 1);
    restore_vertex(p, q->c, &s, 0);
    return pass;
}

/* c's next vertex along the crease of pieces ab (bits), J not: the one such neighbour of c,
 * or UINT32_MAX (none, or more than one). */
static uint32_t next_on_crease(rm_pass *p, const jf_pieces *s, uint32_t J, uint32_t c, int ab)
{
    uint32_t found = UINT32_MAX;
    for (uint32_t i = 0; i < p->r.count[c]; i++) {
        const uint32_t *t = p->r.m->tri + 3 * (size_t)rm_slot(&p->r, c, i);
        for (int k = 0; k < 3; k++) {
            uint32_t y = t[k];
            if (y == c || y == J || y == found || (vanishing(p, s, rm_pos(p, y)) & ab) != ab)
                continue;
            if (found != UINT32_MAX)
                return UINT32_MAX;
            found = y;
        }
    }
    return found;
}

/* The index in s of the bits' lone piece, or of the lowest of several. */
static int piece_index(int bits)
{
    return bits & 1 ? 0 : bits & 2 ? 1 : 2;
}

/* Fills q's c-side for needle t of J's fan with corner c (w the other): c locked, on
 * exactly two of the pieces and nearer J than ISM_RM_CROWD × its next crease vertex; x across
 * c–w free, not yet J's neighbour. False when it is not such a crowd. */
static bool crowd_try(rm_pass *p, const jf_pieces *s, uint32_t J, uint32_t t, uint32_t c,
                      jf_try *q)
{
    const rm_mesh *r = &p->r;
    const ism_mesh *m = r->m;
    int ab = vanishing(p, s, rm_pos(p, c));
    if (!r->locked[c] || r->locked[c] == RM_PINNED || (ab != 3 && ab != 5 && ab != 6))
        return false;
    /* t runs J -> c -> w or J -> w -> c: t1 must run c -> w -> J for the flip's winding */
    int kc = rm_corner(m, t, c);
    uint32_t after = m->tri[3 * (size_t)t + (kc + 1) % 3];
    if (after == J)
        return false; /* the other orientation: c is w of the try with the corners swapped */
    uint32_t w = after, two[2];
    int ne;
    if (!rm_edge_triangles(r, c, w, two, &ne) || ne != 2 || rm_edge_locked(r, c, w) ||
        rm_label(r, two[0]) != rm_label(r, two[1]))
        return false;
    uint32_t t2 = two[0] == t ? two[1] : two[0];
    const uint32_t *k2 = m->tri + 3 * (size_t)t2;
    uint32_t x = k2[0] ^ k2[1] ^ k2[2] ^ c ^ w; /* (rm_flip.c's find_quad) */
    /* c and w keep three triangles or more after the flip; their slots fit jf_saved */
    if (r->locked[x] || x == J || rm_corner(m, t2, J) >= 0 || r->count[c] <= 3 ||
        r->count[w] <= 3 || r->count[c] > ISM_RM_COLLAPSE_MAX_DEGREE ||
        r->count[w] > ISM_RM_COLLAPSE_MAX_DEGREE)
        return false;
    /* c–w on c's crease is the crease's own edge: the flip would cut it */
    if ((vanishing(p, s, rm_pos(p, w)) & ab) == ab)
        return false;
    for (uint32_t i = 0; i < r->count[J]; i++)
        if (rm_corner(m, rm_slot(r, J, i), x) >= 0)
            return false; /* J–x is an edge already */
    uint32_t far = next_on_crease(p, s, J, c, ab);
    const double *at = rm_pos(p, J);
    if (far == UINT32_MAX ||
        !(rm_dist(rm_pos(p, c), at) < ISM_RM_CROWD * rm_dist(rm_pos(p, far), at)))
        return false;
    *q = (jf_try){.J = J, .c = c, .w = w, .x = x, .far = far, .t1 = t, .t2 = t2, .ab = ab};
    return true;
}

/* x onto the crease of the third piece (the one c is not on) and the nearer of c's two,
 * within ISM_RM_JFAN_SNAP_REACH of its distance from J: *snapped (place xx, ∇f xg) when
 * it goes. */
static void snap_x(rm_pass *p, const jf_pieces *s, const jf_try *q, double xx[3], double xg[3],
                   bool *snapped)
{
    int k = piece_index(7 & ~q->ab), a = piece_index(q->ab), b = piece_index(q->ab & ~(1 << a));
    const double *x = rm_pos(p, q->x);
    int near = piece_off(p, s->pc[a], x) <= piece_off(p, s->pc[b], x) ? a : b;
    memcpy(xx, x, 3 * sizeof *xx);
    *snapped = onto_pair(p, s, s->pc[k], s->pc[near], xx, xg) &&
               rm_dist(xx, x) <= ISM_RM_JFAN_SNAP_REACH * rm_dist(x, rm_pos(p, q->J));
}

/* The best operation found at J: the try, c's and x's new places and ∇f there. */
typedef struct jf_best {
    jf_try q;
    double at_j, c[3], cg[3], x[3], xg[3];
    bool snapped;
} jf_best;

/* Every share of crowd try q (J's pieces s) tried, the best that passes into *best. */
static void try_shares(rm_pass *p, const jf_pieces *s, const jf_try *q, jf_best *best)
{
    double xx[3], xg[3] = {0, 0, 0};
    bool snapped;
    uint32_t reg[ISM_RM_JFAN_REGION];
    int n;
    jf_measure before, after;
    if (!region(p, q, reg, &n))
        return;
    snap_x(p, s, q, xx, xg, &snapped);
    measure(p, q, reg, n, &before);
    int a = piece_index(q->ab), b = piece_index(q->ab & ~(1 << a));
    for (size_t h = 0; h < ISM_RM_JFAN_SHARES; h++) {
        double cx[3], cg[3];
        const double *J = rm_pos(p, q->J), *far = rm_pos(p, q->far);
        for (int d = 0; d < 3; d++)
            cx[d] = J[d] + slide_share[h] * (far[d] - J[d]);
        if (!onto_pair(p, s, s->pc[a], s->pc[b], cx, cg) ||
            !trial(p, q, cx, cg, snapped ? xx : NULL, xg, &before, &after, false) ||
            !(after.at_j > best->at_j))
            continue;
        *best = (jf_best){.q = *q, .at_j = after.at_j, .snapped = snapped};
        memcpy(best->c, cx, sizeof cx);
        memcpy(best->cg, cg, sizeof cg);
        memcpy(best->x, xx, sizeof xx);
        memcpy(best->xg, xg, sizeof xg);
    }
}

/* Tries every share of every crowd try at J (each needle of its fan, each of its corners as
 * c) and keeps the best that passes; true when one did. *ok false when out of memory for
 * the flip's slots (nothing changed). */
static bool mend_at(rm_pass *p, uint32_t J, bool *ok)
{
    rm_mesh *r = &p->r;
    rm_fan f;
    jf_pieces s;
    rm_fan_measure(p, J, &f);
    if (!pieces_at(p, J, f.mean_edge, &s))
        return false;
    jf_best best = {.at_j = -1};
    for (uint32_t i = 0; i < r->count[J]; i++) {
        uint32_t t = rm_slot(r, J, i);
        if (!(rm_tri_sine(p, t) < rm_insert_poor()))
            continue;
        for (int k = 0; k < 3; k++) {
            jf_try q;
            uint32_t c = r->m->tri[3 * (size_t)t + k];
            if (c == J || !crowd_try(p, &s, J, t, c, &q))
                continue;
            /* the flip's slots at J and x, before any trial (growing a slot keeps its order) */
            if (!rm_slot_reserve(r, J, 1) || !rm_slot_reserve(r, q.x, 1))
                return *ok = false;
            try_shares(p, &s, &q, &best);
        }
    }
    if (!(best.at_j >= 0))
        return false;
    /* the same operation again, kept: it passes as it did (nothing else changed) */
    jf_measure before, after;
    uint32_t reg[ISM_RM_JFAN_REGION];
    int n;
    region(p, &best.q, reg, &n);
    measure(p, &best.q, reg, n, &before);
    if (!trial(p, &best.q, best.c, best.cg, best.snapped ? best.x : NULL, best.xg, &before,
               &after, true))
        return false;
    if (best.snapped)
        r->locked[best.q.x] = 1; /* on the crease now: kept there, as a snapped vertex is */
    const uint32_t v[4] = {best.q.J, best.q.c, best.q.w, best.q.x};
    for (int k = 0; k < 4; k++) {
        p->active[v[k]] = 1, p->touched[v[k]] = 2;
        if (p->crease_tried)
            p->crease_tried[v[k]] = NAN;
    }
    return true;
}

/* J's where a mend failed since the last one kept, remembered so that J's other needles do
 * not read its pieces and run its trials again (a failed mend changes nothing, so it would
 * fail again until some mend elsewhere changes the mesh): a triple point's fan holds a few. */
#define ISM_RM_JFAN_FAILED 8

typedef struct jf_failed {
    uint32_t v[ISM_RM_JFAN_FAILED];
    int n;
} jf_failed;

static bool failed_has(const jf_failed *f, uint32_t J)
{
    for (int i = 0; i < f->n; i++)
        if (f->v[i] == J)
            return true;
    return false;
}

/* J remembered (the oldest forgotten when full: it is then only tried again). */
static void failed_add(jf_failed *f, uint32_t J)
{
    if (f->n < ISM_RM_JFAN_FAILED)
        f->v[f->n++] = J;
    else {
        memmove(f->v, f->v + 1, (ISM_RM_JFAN_FAILED - 1) * sizeof *f->v);
        f->v[ISM_RM_JFAN_FAILED - 1] = J;
    }
}

size_t rm_junction_fan_mend(rm_pass *p, bool *ok)
{
    const ism_mesh *m = p->r.m;
    size_t made = 0;
    jf_failed failed = {.n = 0};
    if (!ism_tape_has_min_max(p->f))
        return 0;
    for (size_t t = 0; t < m->ntris && *ok; t++) {
        if (p->r.dead[t] || !(rm_tri_sine(p, (uint32_t)t) < rm_insert_poor()))
            continue;
        for (int k = 0; k < 3; k++) {
            uint32_t J = m->tri[3 * t + k];
            if (!p->r.locked[J] || failed_has(&failed, J) || !rm_junction_vertex_on(p, J))
                continue;
            if (mend_at(p, J, ok)) {
                made++;
                failed.n = 0; /* the mesh changed: every J may mend now */
                break;
            }
            if (*ok)
                failed_add(&failed, J);
        }
    }
    p->flips += made;
    return made;
}
