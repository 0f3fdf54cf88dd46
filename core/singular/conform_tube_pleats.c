/* conform_tube_pleats.c — growing a tube's cut where its rim steps backwards along a lone
 * closed double curve. Where two sheets cross at a small angle the polygoniser pleats beside
 * the curve (two unit spheres crossing at 29°, depth 7: within 3–4 cells of the double
 * circle, where the sheets are under two cells apart), and the tube's rim (about 3 cells)
 * runs through the pleats: a rim loop's feet on the curve go against the loop's winding, and
 * the zip's rings and triangles turn over there (902 edges turned against ∇f in the preset's
 * own box). The cut then grows along those stretches only, the rest of the tube left as cut:
 *
 *     rim   ───●────●──●───●────●───     feet s: 1  2  4  3  5  (4 → 3 steps back)
 *     curve ═══════════════════════════  the stretch [3, 4] is cut wider
 *
 * The radius along the curve is R on the stretches (held FOLD_HOLD R past them) and falls
 * back to the tube's r over FOLD_RAMP R: a round cap at a stretch's end would turn the rim
 * across the curve there (crossing spheres, depth 7, own box: 24 turned edges with caps,
 * 15 with the ramp, 902 without growth). */
#include "core/singular/conform_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Each growth cuts FOLD_GROW times wider than the last, up to FOLD_CELLS finest cells
 * (crossing spheres, depth 7, own box: 80, 48, 16, 0 backward steps at 3.0, 3.6, 4.3, 5.2
 * cells; the figure-8 Klein bottle, depth 8: 9, 0 at 2.5, 3.0); the first growth that does
 * not lower the backward steps, or that changes the number of rim loops (two sheets' rims
 * merged), is put back and ends the growth: a curve whose rim keeps stepping back costs one
 * growth of its stretches. */
#define FOLD_GROW 1.2
#define FOLD_CELLS 8.0
/* The full radius is held this many R past a stretch's backward steps, and falls to r over
 * this many R beyond (a slope (R − r) / (FOLD_RAMP R) under 1/2). */
#define FOLD_HOLD 0.5
#define FOLD_RAMP 2.0
/* Growth is for pleats along part of a curve: when the first growth's pieces (held and
 * ramped) would cover more than this share of it, the pleats run all round (crossing spheres
 * at 29°, depth 7: 100%, 94%, 84% at the three growths) and every growth re-cuts and
 * re-chains nearly the whole tube — conformance 193M → 439M instructions, the singular stage
 * 0.21 → 0.43 of the polygoniser, over issue 13's 0.25 — so the curve is left as cut. The
 * figure-8 Klein bottle at depth 8 covers 28% (conformance +15%; its turned-over edges 69 /
 * 69 / 27 → 3 / 3 / 14 raw, 34 / 34 / 8 → 0 / 0 / 0 after the quality pass). */
#define FOLD_SHARE 0.5
/* A rim vertex lies about the cut's radius from the curve (farther only beside long edges):
 * its foot is looked for within this many radii first. */
#define RIM_NEAR 1.5

/* Arclength spans of a closed curve (2 per span: from, to) and the backward steps found. */
typedef struct spans {
    double *ab;
    size_t n, cap;
    size_t back;
} spans;

static void spans_free(spans *sp)
{
    free(sp->ab);
    memset(sp, 0, sizeof *sp);
}

static bool push_span(spans *sp, double a, double b)
{
    if (sp->n == sp->cap) {
        size_t cap = sp->cap ? 2 * sp->cap : 16;
        double *ab = realloc(sp->ab, 2 * cap * sizeof *ab);
        if (!ab)
            return false;
        sp->ab = ab;
        sp->cap = cap;
    }
    sp->ab[2 * sp->n] = a;
    sp->ab[2 * sp->n + 1] = b;
    sp->n++;
    return true;
}

/* The mesh vertices' feet on the curve, found once for every growth (the cut marks
 * triangles dead, it moves no vertex): d[v] the distance (known[v] = 1), or nothing within
 * -d[v] (known[v] = 2); s[v] the foot's arclength. */
typedef struct feet {
    const cf_polyline *pl;
    double *d, *s;
    uint8_t *known;
} feet;

static bool feet_init(feet *f, const cf_ctx *c, const cf_polyline *pl)
{
    size_t n = c->m->nverts + 1;
    f->pl = pl;
    f->d = malloc(n * sizeof *f->d);
    f->s = malloc(n * sizeof *f->s);
    f->known = calloc(n, 1);
    return f->d && f->s && f->known;
}

static void feet_free(feet *f)
{
    free(f->d);
    free(f->s);
    free(f->known);
}

/* Vertex v's distance to the curve and its foot *s; INFINITY when nothing is within. */
static double foot_of(const cf_ctx *c, feet *f, uint32_t v, double within, double *s)
{
    if (f->known[v] == 1 || (f->known[v] == 2 && within <= -f->d[v])) {
        *s = f->s[v];
        return f->known[v] == 1 ? f->d[v] : INFINITY;
    }
    double d = cf_polyline_nearest(f->pl, c->m->pos + 3 * (size_t)v, within, &f->s[v], NULL);
    f->known[v] = isfinite(d) ? 1 : 2;
    f->d[v] = isfinite(d) ? d : -within;
    *s = f->s[v];
    return d;
}

/* s − t wrapped into (−L/2, L/2]: the short way round a closed curve of length L. */
static double wrapped_step(double s, double t, double L)
{
    double d = s - t;
    return d - L * round(d / L);
}

/* The backward steps of loop l round pl (feet against the loop's winding) into sp; none
 * when the loop does not wind round pl or a vertex has no foot. False when out of memory. */
static bool loop_pleats(const cf_ctx *c, feet *ft, double near, const cf_loop *l, spans *sp)
{
    const cf_polyline *pl = ft->pl;
    double *s = malloc((l->n + 1) * sizeof *s);
    if (!s)
        return false;
    for (size_t j = 0; j < l->n; j++)
        if (!isfinite(foot_of(c, ft, l->v[j], near, &s[j])) &&
            !isfinite(foot_of(c, ft, l->v[j], INFINITY, &s[j]))) {
            free(s);
            return true;
        }
    double total = 0;
    for (size_t j = 0; j < l->n; j++)
        total += wrapped_step(s[(j + 1) % l->n], s[j], pl->length);
    bool ok = true;
    /* a loop not winding round the curve is a rim round a piece of sheet */
    for (size_t j = 0; ok && fabs(total) > pl->length / 2 && j < l->n; j++) {
        double d = wrapped_step(s[(j + 1) % l->n], s[j], pl->length);
        if (d * total < 0) {
            sp->back++;
            ok = push_span(sp, s[j] + fmin(d, 0), s[j] + fmax(d, 0));
        }
    }
    free(s);
    return ok;
}

/* The backward steps of the closed loops of ls round the curve, whose vertices mostly lie
 * within near of it (searched that far first: one look in the curve's grid, not a widening
 * search). False when out of memory. */
static bool find_pleats(const cf_ctx *c, feet *ft, double near, const cf_loops *ls, spans *sp)
{
    memset(sp, 0, sizeof *sp);
    for (size_t i = 0; i < ls->n; i++)
        if (ls->l[i].closed && ls->l[i].n >= 3 && !loop_pleats(c, ft, near, &ls->l[i], sp))
            return false;
    return true;
}

static int cmp_span(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return a < b ? -1 : a > b;
}

/* The spans grown by margin on a closed curve of length L, their starts in [0, L), sorted
 * and merged (the last one wrapping past L into the first merged too); one span [0, L] when
 * they cover the curve. */
static void merge_spans(spans *sp, double margin, double L)
{
    for (size_t i = 0; i < sp->n; i++) {
        double a = sp->ab[2 * i] - margin, b = sp->ab[2 * i + 1] + margin;
        double shift = L * floor(a / L);
        sp->ab[2 * i] = a - shift;
        sp->ab[2 * i + 1] = fmin(b - shift, a - shift + L);
    }
    if (sp->n)
        qsort(sp->ab, sp->n, 2 * sizeof *sp->ab, cmp_span);
    size_t m = 0;
    for (size_t i = 0; i < sp->n; i++) {
        if (m > 0 && sp->ab[2 * i] <= sp->ab[2 * m - 1]) {
            sp->ab[2 * m - 1] = fmax(sp->ab[2 * m - 1], sp->ab[2 * i + 1]);
            continue;
        }
        sp->ab[2 * m] = sp->ab[2 * i];
        sp->ab[2 * m + 1] = sp->ab[2 * i + 1];
        m++;
    }
    if (m > 1 && sp->ab[2 * m - 1] - L >= sp->ab[0]) { /* the last wraps into the first */
        sp->ab[1] = fmax(sp->ab[2 * m - 1] - L, sp->ab[1]);
        sp->ab[0] = sp->ab[2 * m - 2] - L;
        m--;
    }
    for (size_t i = 0; i < m; i++)
        if (sp->ab[2 * i + 1] - sp->ab[2 * i] >= L) {
            sp->ab[0] = 0;
            sp->ab[1] = L;
            m = 1;
        }
    sp->n = m;
}

/* The point of the closed polyline at arclength t (any real: taken modulo its length). */
static void point_at(const cf_polyline *pl, double t, double out[3])
{
    t -= pl->length * floor(t / pl->length);
    size_t lo = 0, hi = pl->n - 1; /* the last i with s[i] <= t */
    while (lo < hi) {
        size_t mid = (lo + hi + 1) / 2;
        if (pl->s[mid] <= t)
            lo = mid;
        else
            hi = mid - 1;
    }
    const double *a = pl->p + 3 * lo, *b = pl->p + 3 * ((lo + 1) % pl->n);
    double len = pl->s[lo + 1] - pl->s[lo], u = len > 0 ? (t - pl->s[lo]) / len : 0;
    for (int k = 0; k < 3; k++)
        out[k] = a[k] + u * (b[k] - a[k]);
}

/* The points of the closed curve from arclength a to b (a < b < a + L): both ends and the
 * curve's points between (n of them). */
static double *span_points(const cf_polyline *pl, double a, double b, size_t *n)
{
    double *p = malloc(3 * (pl->n + 2) * sizeof *p), shift = pl->length * floor(a / pl->length);
    if (!p)
        return NULL;
    a -= shift;
    b -= shift;
    size_t k = 0, j = 0;
    point_at(pl, a, p + 3 * k++);
    while (j < pl->n && pl->s[j] <= a)
        j++;
    for (; j < 2 * pl->n; j++) {
        double t = pl->s[j % pl->n] + pl->length * (double)(j / pl->n);
        if (!(t < b))
            break;
        memcpy(p + 3 * k++, pl->p + 3 * (j % pl->n), 3 * sizeof *p);
    }
    point_at(pl, b, p + 3 * k++);
    *n = k;
    return p;
}

/* The growth's cutter: the curve, the spans cut at full radius R (merged, held), the tube's
 * radius r, the ramp's length, and the pieces of the curve the candidates are gathered
 * along (the spans grown by the ramp). */
typedef struct taper {
    const cf_polyline *pl;
    feet *ft;
    const spans *full;
    double r, R, ramp;
    cf_polyline *piece;
    double **piece_pts;
    size_t npieces;
} taper;

static void taper_free(taper *tp)
{
    for (size_t i = 0; i < tp->npieces; i++) {
        cf_polyline_free(&tp->piece[i]);
        free(tp->piece_pts[i]);
    }
    free(tp->piece);
    free(tp->piece_pts);
}

/* The pieces of tp->pl along the spans of tp->full grown by the ramp (one closed copy when
 * they cover the curve). False when out of memory. */
static bool taper_pieces(taper *tp, double step)
{
    const cf_polyline *pl = tp->pl;
    spans sp = {malloc((2 * tp->full->n + 1) * sizeof *sp.ab), tp->full->n, tp->full->n, 0};
    tp->piece = calloc(sp.n + 1, sizeof *tp->piece);
    tp->piece_pts = calloc(sp.n + 1, sizeof *tp->piece_pts);
    bool ok = sp.ab && tp->piece && tp->piece_pts;
    if (ok) {
        memcpy(sp.ab, tp->full->ab, 2 * sp.n * sizeof *sp.ab);
        merge_spans(&sp, tp->ramp, pl->length);
    }
    for (size_t i = 0; ok && i < sp.n; i++) {
        bool whole = sp.ab[2 * i + 1] - sp.ab[2 * i] >= pl->length;
        size_t m = pl->n;
        double *p = whole ? malloc(3 * m * sizeof *p) : span_points(pl, sp.ab[2 * i],
                                                                    sp.ab[2 * i + 1], &m);
        if (p && whole)
            memcpy(p, pl->p, 3 * m * sizeof *p);
        tp->piece_pts[tp->npieces] = p;
        ok = p && cf_polyline_init(&tp->piece[tp->npieces++], p, m, whole, step);
    }
    spans_free(&sp);
    return ok;
}

/* The cut's radius at arclength s: R on the spans, down to r over the ramp beyond. */
static double radius_at(const taper *tp, double s)
{
    double L = tp->pl->length, gap = INFINITY;
    s -= L * floor(s / L);
    for (size_t i = 0; i < tp->full->n && gap > 0; i++) {
        double a = tp->full->ab[2 * i], b = tp->full->ab[2 * i + 1];
        if ((s >= a && s <= b) || (s + L >= a && s + L <= b) || (s - L >= a && s - L <= b))
            gap = 0;
        double to_a = a - s - L * floor((a - s) / L), from_b = s - b - L * floor((s - b) / L);
        gap = fmin(gap, fmin(to_a, from_b));
    }
    return tp->r + (tp->R - tp->r) * fmax(0, 1 - gap / tp->ramp);
}

/* A point of triangle t (corners, then edge midpoints and centroid) within the radius at its
 * foot. */
static bool tri_in_taper(const cf_ctx *c, uint32_t t, void *arg)
{
    const taper *tp = arg;
    const uint32_t *v = c->m->tri + 3 * (size_t)t;
    /* a triangle with a point within R has every corner within R + its longest edge */
    double edge = sqrt(cf_triangle_longest_edge2(c->m, t)), s, over = INFINITY;
    for (int k = 0; k < 3; k++) {
        double d = foot_of(c, tp->ft, v[k], tp->R + edge, &s);
        if (!isfinite(d) || d > tp->R + edge)
            return false;
        over = fmin(over, d > tp->R ? d - tp->R : d - radius_at(tp, s));
        if (over <= 0)
            return true;
    }
    /* the other samples lie within an edge of a corner, where the distance changes by at most
     * that and the radius by less (its slope is under 1) */
    if (over > 2 * edge)
        return false;
    const double *P[3] = {c->m->pos + 3 * (size_t)v[0], c->m->pos + 3 * (size_t)v[1],
                          c->m->pos + 3 * (size_t)v[2]};
    for (int j = 0; j < 4; j++) {
        double q[3];
        for (int k = 0; k < 3; k++)
            q[k] = j < 3 ? (P[j][k] + P[(j + 1) % 3][k]) / 2 : (P[0][k] + P[1][k] + P[2][k]) / 3;
        double d = cf_polyline_nearest(tp->pl, q, tp->R, &s, NULL);
        if (isfinite(d) && d <= radius_at(tp, s))
            return true;
    }
    return false;
}

static bool gather_taper(cf_ctx *c, void *arg, cf_tris *out)
{
    const taper *tp = arg;
    return cf_gather_near_curves(c, tp->piece, tp->npieces, tp->R, out);
}

/* The cut grown to radius R along the spans of sp (held and ramped, FOLD_HOLD), the whole
 * rim chained again into ls. False when out of memory. */
static bool grow_at(cf_ctx *c, feet *ft, spans *sp, double r, double R, uint32_t **rm,
                    size_t *nrm, cf_loops *ls)
{
    const cf_polyline *pl = ft->pl;
    merge_spans(sp, FOLD_HOLD * R, pl->length);
    taper tp = {pl, ft, sp, r, R, FOLD_RAMP * R, NULL, NULL, 0};
    cf_cutter cut = {tri_in_taper, gather_taper, &tp};
    bool ok = taper_pieces(&tp, CF_RHO_CELLS * c->cell) && cf_cut_more(c, &cut, rm, nrm, ls);
    taper_free(&tp);
    return ok;
}

/* Revives the triangles of the sorted list now (n) missing from the sorted list before. */
static void revive_since(cf_ctx *c, const uint32_t *before, size_t nb, const uint32_t *now,
                         size_t n)
{
    for (size_t i = 0, j = 0; i < n; i++) {
        while (j < nb && before[j] < now[i])
            j++;
        if (j == nb || before[j] != now[i])
            c->dead[now[i]] = 0;
    }
}

/* The share of a closed curve of length L that the spans of sp, grown by margin, cover. */
static double span_share(const spans *sp, double margin, double L)
{
    spans cp = {NULL, sp->n, sp->n, 0};
    if (!sp->n)
        return 0;
    cp.ab = malloc(2 * sp->n * sizeof *cp.ab);
    if (!cp.ab)
        return 1; /* out of memory: as if all round (no growth) */
    memcpy(cp.ab, sp->ab, 2 * sp->n * sizeof *cp.ab);
    merge_spans(&cp, margin, L);
    double len = 0;
    for (size_t i = 0; i < cp.n; i++)
        len += cp.ab[2 * i + 1] - cp.ab[2 * i];
    spans_free(&cp);
    return len / L;
}

bool cf_cut_past_pleats(cf_ctx *c, const cf_polyline *pl, double r, cf_loops *ls,
                        uint32_t **rm, size_t *nrm)
{
    if (!pl->closed || !(pl->length > 0))
        return true;
    spans sp = {0};
    feet ft;
    bool ok = feet_init(&ft, c, pl) && find_pleats(c, &ft, RIM_NEAR * r, ls, &sp);
    size_t nloops = ls->n;
    if (ok && span_share(&sp, (FOLD_HOLD + FOLD_RAMP) * r * FOLD_GROW, pl->length) > FOLD_SHARE)
        sp.back = 0; /* pleats all round: left as cut */
    for (double R = r * FOLD_GROW; ok && sp.back > 0 && !c->stopped && R <= FOLD_CELLS * c->cell;
         R *= FOLD_GROW) {
        size_t nb = *nrm;
        uint32_t *before = malloc((nb + 1) * sizeof *before);
        cf_loops was = *ls, now = {0};
        spans next = {0};
        if (before)
            memcpy(before, *rm, nb * sizeof *before);
        ok = before && grow_at(c, &ft, &sp, r, R, rm, nrm, &now) &&
             (c->stopped || find_pleats(c, &ft, RIM_NEAR * R, &now, &next));
        bool keep = ok && !c->stopped && now.n == nloops && next.back < sp.back;
        if (keep || !ok || c->stopped) { /* kept, or about to be undone whole */
            cf_loops_free(&was);
            *ls = now;
        } else { /* put back */
            revive_since(c, before, nb, *rm, *nrm);
            memcpy(*rm, before, nb * sizeof *before);
            *nrm = nb;
            cf_loops_free(&now);
        }
        free(before);
        spans_free(&sp);
        sp = next;
        if (!keep)
            break;
    }
    spans_free(&sp);
    feet_free(&ft);
    return ok;
}
