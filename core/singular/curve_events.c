/* curve_events.c — box-face clipping, pinch location, running into singular points, and
 * recording the points tracing finds. See curve_events.h. */
#include "core/singular/curve_events.h"

#include <string.h>

/* Newton iterations at a clip or pinch station: near a pinch the Jacobian is nearly singular
 * in one direction and Newton converges only linearly (halving the error), so it needs
 * ~log2(step / tolerance) ≈ 40 iterations at worst. */
#define CEVENT_NEWTON_IT 60

/* Regula falsi iterations for a pinch (Illinois converges superlinearly; the cap only
 * guards against a determinant that is noise). */
#define CEVENT_PINCH_IT 100

/* A pinch is located when its bracket is below this × box diagonal: a tenth of the 1e-9
 * the locus promises for its points. */
#define CEVENT_PINCH_TOL_REL 1e-10

/* An existing point with a large enclosure (an uncertified cluster) still catches a path
 * only this close (× the search's finest cell): a curve passing a cell from an isolated
 * point does not end there. */
#define CEVENT_SNAP_MAX_CELLS 0.125

bool ism_cevent_clip(ism_ctracer *tr, const ism_cpoint *cur, ism_cpoint *nxt)
{
    double a[3], b[3];
    memcpy(a, cur->p, sizeof a);
    memcpy(b, nxt->p, sizeof b);
    double reach = ism_dist3(a, b) + tr->jet.tol;
    for (int tries = 0; tries < 3 && !ism_ctracer_inside(tr, b); tries++) {
        int axis = -1;
        double lam = 2.0, face = 0.0;
        for (int k = 0; k < 3; k++) {
            int side = ism_ctracer_side(tr, k, b[k]);
            double f = tr->box[side < 0 ? k : k + 3];
            double l = side ? (f - a[k]) / (b[k] - a[k]) : 2.0;
            if (l < lam)
                lam = fmax(l, 0.0), axis = k, face = f;
        }
        if (axis < 0)
            return false; /* NaN */
        double s[3], P[2][3] = {{0, 0, 0}, {0, 0, 0}}, r[3];
        for (int k = 0; k < 3; k++)
            s[k] = a[k] + lam * (b[k] - a[k]);
        s[axis] = face;
        P[0][(axis + 1) % 3] = 1.0;
        P[1][(axis + 2) % 3] = 1.0;
        if (!ism_cjet_correct(&tr->jet, s, P, cur->n, reach, CEVENT_NEWTON_IT, r, NULL))
            return false;
        r[axis] = face; /* exactly on the face (Newton moved only within it) */
        memcpy(b, r, sizeof b);
    }
    if (!ism_ctracer_inside(tr, b))
        return false;
    ism_cjet_frame(&tr->jet, b, cur->t, nxt);
    return true;
}

void ism_cevent_locate_pinch(ism_ctracer *tr, const ism_cpoint *a, const ism_cpoint *b,
                             ism_cpoint *out, double *radius)
{
    *out = fabs(a->D) < fabs(b->D) ? *a : *b;
    *radius = tr->jet.tol;
    if (b->D == 0.0)
        return;
    double u[3] = {b->p[0] - a->p[0], b->p[1] - a->p[1], b->p[2] - a->p[2]};
    double len = sqrt(ism_dot3(u, u)), E[2][3];
    for (int k = 0; k < 3; k++)
        u[k] /= len;
    ism_across_least3(u, E);
    double lo = 0.0, hi = 1.0, dlo = a->D, dhi = b->D;
    int side = 0; /* which end moved last (Illinois halves the other end's value) */
    for (int it = 0; it < CEVENT_PINCH_IT && (hi - lo) * len > CEVENT_PINCH_TOL_REL * tr->diag;
         it++) {
        double l = (lo * dhi - hi * dlo) / (dhi - dlo);
        if (!(l > lo && l < hi))
            l = 0.5 * (lo + hi);
        double s[3], q[3];
        for (int k = 0; k < 3; k++)
            s[k] = a->p[k] + l * len * u[k];
        if (!ism_cjet_correct(&tr->jet, s, E, E, 0.5 * len, CEVENT_NEWTON_IT, q, NULL))
            break;
        ism_cpoint m;
        ism_cjet_frame(&tr->jet, q, a->t, &m);
        if (fabs(m.D) <= fabs(out->D))
            *out = m;
        if (m.D == 0.0) {
            lo = hi = l;
            break;
        }
        if ((m.D < 0) == (dlo < 0)) {
            lo = l, dlo = m.D;
            if (side < 0)
                dhi *= 0.5;
            side = -1;
        } else {
            hi = l, dhi = m.D;
            if (side > 0)
                dlo *= 0.5;
            side = 1;
        }
    }
    *radius = fmax((hi - lo) * len, tr->jet.tol);
}

static double snap_radius(const ism_ctracer *tr, const ism_sing_point *p)
{
    return fmax(tr->snap, fmin(p->radius, CEVENT_SNAP_MAX_CELLS * tr->cell));
}

int ism_cevent_hit_point(const ism_ctracer *tr, const double a[3], const double b[3],
                         int ignore)
{
    int best = -1;
    double best_u = 2.0;
    for (size_t j = 0; j < tr->io->npoints; j++) {
        const ism_sing_point *p = &tr->io->points[j];
        double u;
        if ((int)j != ignore && ism_dist_segment(p->p, a, b, &u) <= snap_radius(tr, p) &&
            u < best_u)
            best = (int)j, best_u = u;
    }
    return best;
}

int ism_cevent_point(ism_ctracer *tr, const ism_cpoint *c, int type, double radius)
{
    for (size_t j = 0; j < tr->io->npoints; j++) {
        ism_sing_point *q = &tr->io->points[j];
        if (ism_dist3(q->p, c->p) <= snap_radius(tr, q)) {
            if (type == ISM_SING_PINCH && !q->certified) /* a candidate the search could not */
                q->type = ISM_SING_PINCH;                 /* type: it is on a curve */
            return (int)j;
        }
    }
    ism_sing_point sp = {
        .radius = radius,
        .type = type,
        .certified = false,
        .residual_f = fabs(c->f),
        .residual_grad = c->grad,
        .cones = -1,
    };
    memcpy(sp.p, c->p, sizeof sp.p);
    memcpy(sp.eig, c->eig, sizeof sp.eig);
    if (tr->io->npoints >= INT32_MAX || !ism_locus_add_point(tr->io, &sp)) {
        tr->oom = true;
        return -1;
    }
    ism_cindex_mark_ball(&tr->idx, c->p, tr->delta);
    return (int)tr->io->npoints - 1;
}
