/* sp_place.c — balancing offsets of the simplified mesh's vertices (sp_place.h): a convex
 * piecewise-linear minimax in one unknown, solved exactly on the linear model, then checked by
 * measuring every stencil at the result. */
#include "core/remesh/sp_place.h"
#include "core/remesh/rm_bound.h"
#include "core/util/vec3.h"

#include <math.h>

/* The offset is searched within this × max_error each way: no vertex may lie farther off. */
#define SP_PLACE_RANGE 1.0
/* A placement whose linear model stays above this × the caller's limit is not measured: the
 * model is good to second order in the offset (a few per cent at these sizes). */
#define SP_PLACE_SLACK 1.05
/* The vertex's and centroids' lines alone refuse a placement only above the slack by this
 * factor: their best can exceed the best over all the lines by rounding alone. */
#define SP_PLACE_SUBSET_MARGIN (1 + 1e-9)

/* Adds a stencil when there is room. */
static bool add(sp_stencil *s, int *n, const double *a, const double *b)
{
    if (*n >= SP_MAX_STENCILS)
        return false;
    s[*n].a = a, s[*n].b = b;
    (*n)++;
    return true;
}

int sp_stencils(const rm_pass *p, const uint32_t *fan, uint32_t n, uint32_t v, uint32_t w,
                sp_stencil *s)
{
    int ns = 0;
    uint32_t seen[SP_MAX_STENCILS];
    int nseen = 0;
    if (!add(s, &ns, NULL, NULL))
        return 0;
    for (uint32_t i = 0; i < n; i++) {
        const uint32_t *c = p->r.m->tri + 3 * fan[i];
        const double *other[2];
        int no = 0;
        for (int k = 0; k < 3; k++) {
            if (c[k] == v || c[k] == w)
                continue;
            if (no < 2)
                other[no] = p->r.m->pos + 3 * (size_t)c[k];
            no++;
            int j = 0;
            while (j < nseen && seen[j] != c[k])
                j++;
            if (j == nseen && nseen < SP_MAX_STENCILS) {
                seen[nseen++] = c[k];
                if (!add(s, &ns, p->r.m->pos + 3 * (size_t)c[k], NULL))
                    return 0;
            }
        }
        if (no == 2 && !add(s, &ns, other[0], other[1]))
            return 0;
    }
    return ns;
}

/* The stencil's point with the moving vertex at x, and its weight in the vertex's offset. */
static double point(const sp_stencil *s, const double *x, double y[3])
{
    if (s->a && s->b)
        rm_centroid(x, s->a, s->b, y);
    for (int k = 0; k < 3 && !(s->a && s->b); k++)
        y[k] = !s->a ? x[k] : 0.5 * (x[k] + s->a[k]);
    return !s->a ? 1.0 : !s->b ? 0.5 : 1.0 / 3;
}

/* The largest and smallest signed distance among the stencils of each weight (the vertex,
 * the midpoints, the centroids): the largest |e_k + w_k δ| is the largest of six lines. */
typedef struct lines {
    double w[3], hi[3], lo[3];
} lines;

static int weight_class(double w) { return w == 1.0 ? 0 : w == 0.5 ? 1 : 2; }

static double model(const lines *l, double delta)
{
    double worst = 0;
    for (int c = 0; c < 3; c++)
        if (l->hi[c] >= l->lo[c]) { /* finite lines: no libm fmax calls */
            double up = l->hi[c] + l->w[c] * delta, down = -(l->lo[c] + l->w[c] * delta);
            double m = up > down ? up : down;
            worst = m > worst ? m : worst;
        }
    return worst;
}

/* The offset within ±range where the largest of the six lines is least: where a rising line
 * (a largest distance, plus w δ) meets a falling one (a smallest, minus w δ), or an end. */
static double best_offset(const lines *l, double range)
{
    double best = 0, worst = model(l, 0);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            if (!(l->hi[i] >= l->lo[i]) || !(l->hi[j] >= l->lo[j]))
                continue;
            double d = fmax(-range, fmin(range, -(l->lo[j] + l->hi[i]) / (l->w[i] + l->w[j])));
            double m = model(l, d);
            if (m < worst)
                best = d, worst = m;
        }
    return best;
}

/* Adds the signed distances of the stencils of one kind (midpoints, or the others) with the
 * moving point at x to the lines. False where f cannot be measured. */
static bool add_lines(rm_pass *p, const sp_stencil *s, int n, bool midpoints, const double *x,
                      lines *l)
{
    double y[3];
    for (int k = 0; k < n; k++) {
        if ((s[k].a && !s[k].b) != midpoints)
            continue;
        int c = weight_class(point(&s[k], x, y));
        double e = rm_bound_signed(p, y);
        if (!isfinite(e))
            return false;
        l->hi[c] = e > l->hi[c] ? e : l->hi[c]; /* e is finite */
        l->lo[c] = e < l->lo[c] ? e : l->lo[c];
    }
    return true;
}

bool sp_place(rm_pass *p, const sp_stencil *s, int n, double limit, double x[3], double g[3],
              double *before)
{
    lines l = {{1.0, 0.5, 1.0 / 3}, {-INFINITY, -INFINITY, -INFINITY},
               {INFINITY, INFINITY, INFINITY}};
    double range = SP_PLACE_RANGE * p->max_error, most = SP_PLACE_SLACK * limit;
    *before = INFINITY;
    /* the vertex and the centroids first: the model's best over some of the lines is no
       worse than over all of them, so when it is already above the limit the midpoints
       need not be measured */
    if (!add_lines(p, s, n, false, x, &l) ||
        !(model(&l, best_offset(&l, range)) <= most * SP_PLACE_SUBSET_MARGIN) ||
        !add_lines(p, s, n, true, x, &l))
        return false;
    *before = model(&l, 0);
    if (!(*before > 0))
        return false;
    double delta = best_offset(&l, range);
    if (!(model(&l, delta) <= most))
        return false; /* the model already says no: nothing to measure */
    if (!rm_bound_gradient(p, x, g)) /* measured with the vertex's stencil above */
        return false;
    double gn = sqrt(ism_dot3(g, g));
    for (int k = 0; k < 3; k++)
        x[k] += delta * g[k] / gn;
    return rm_bound_gradient(p, x, g); /* the measure at x that follows takes it from there */
}

double sp_measure(rm_pass *p, const sp_stencil *s, int n, const double x[3], double stop)
{
    double worst = 0, y[3];
    for (int k = 0; k < n && worst <= stop; k++) {
        point(&s[k], x, y);
        double d = rm_bound_distance(p, y, stop); /* above stop: one step; never NaN */
        worst = d > worst ? d : worst;
    }
    return isfinite(worst) ? worst : INFINITY;
}

bool sp_offset_vertex(rm_pass *p, uint32_t v)
{
    const rm_mesh *r = &p->r;
    sp_stencil s[SP_MAX_STENCILS];
    int n = sp_stencils(p, r->vt + r->start[v], r->count[v], v, v, s);
    double x[3], g[3], before;
    for (int k = 0; k < 3; k++)
        x[k] = r->m->pos[3 * (size_t)v + k];
    rm_fan f;
    rm_fan_measure(p, v, &f);
    if (!n || !sp_place(p, s, n, p->max_error, x, g, &before) ||
        !rm_fan_accepts(p, v, x, &f) || /* the shape first: it measures nothing */
        !(sp_measure(p, s, n, x, before) < before))
        return false;
    rm_commit_move(p, v, x, g);
    p->moves++;
    return true;
}
