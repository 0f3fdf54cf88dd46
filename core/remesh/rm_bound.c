/* rm_bound.c — distances to f = 0 measured with a Newton step, and the bound checks built on
 * them (rm_bound.h). */
#include "core/remesh/rm_bound.h"
#include "core/util/vec3.h"

#include <math.h>

/* f/|∇f| at x into *s1 and, unless |*s1| > limit, where the Newton step from x lands into *s2
 * (0 otherwise). False where ∇f vanishes or f is not finite. */
static bool two_steps(rm_pass *p, const double x[3], double limit, double *s1, double *s2)
{
    double g[3], fv = ism_eval_gradient(p->f, p->ws, x[0], x[1], x[2], g);
    double g2 = ism_dot3(g, g), gn = sqrt(g2);
    *s2 = 0;
    if (!isfinite(fv) || !(gn > p->gthresh))
        return false;
    *s1 = fv / gn;
    if (fabs(*s1) > limit)
        return true;
    double s = fv / g2, y[3] = {x[0] - s * g[0], x[1] - s * g[1], x[2] - s * g[2]};
    double h[3], fy = ism_eval_gradient(p->f, p->ws, y[0], y[1], y[2], h), hn = sqrt(ism_dot3(h, h));
    if (!isfinite(fy) || !(hn > p->gthresh))
        return false;
    *s2 = fy / hn;
    return true;
}

double rm_bound_distance(rm_pass *p, const double x[3], double limit)
{
    double s1, s2;
    return two_steps(p, x, limit, &s1, &s2) ? fabs(s1) + fabs(s2) : INFINITY;
}

double rm_bound_signed(rm_pass *p, const double x[3])
{
    double s1, s2;
    return two_steps(p, x, -1, &s1, &s2) ? s1 : INFINITY;
}

bool rm_bound_edge(rm_pass *p, const double *a, const double *b)
{
    double m[3] = {0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])};
    return rm_bound_distance(p, m, p->max_error) <= p->max_error;
}

bool rm_bound_triangle(rm_pass *p, const double *a, const double *b, const double *c)
{
    double m[3];
    for (int k = 0; k < 3; k++)
        m[k] = (a[k] + b[k] + c[k]) / 3;
    return rm_bound_distance(p, m, p->max_error) <= p->max_error;
}

double rm_bound_fan_worst(rm_pass *p, uint32_t v, const double *x)
{
    const rm_mesh *r = &p->r;
    const double *P = r->m->pos;
    double worst = 0;
    for (uint32_t i = 0; i < r->count[v]; i++) {
        const uint32_t *t = r->m->tri + 3 * r->vt[r->start[v] + i];
        const double *q[3];
        for (int k = 0; k < 3; k++)
            q[k] = t[k] == v ? x : P + 3 * (size_t)t[k];
        int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
        double g[3], m[3];
        for (int j = 0; j < 3; j++) {
            g[j] = (q[0][j] + q[1][j] + q[2][j]) / 3;
            m[j] = 0.5 * (x[j] + q[(k + 1) % 3][j]);
        }
        /* each edge at v is the next edge of exactly one triangle of a closed fan */
        worst = fmax(worst, fmax(rm_bound_distance(p, g, INFINITY),
                                 rm_bound_distance(p, m, INFINITY)));
    }
    return fmax(worst, rm_bound_distance(p, x, INFINITY));
}

bool rm_bound_fan(rm_pass *p, uint32_t v, const double *x)
{
    double now = rm_bound_fan_worst(p, v, x);
    return now <= p->max_error || now <= rm_bound_fan_worst(p, v, p->r.m->pos + 3 * (size_t)v);
}
