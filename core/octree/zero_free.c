/* zero_free.c — proving a node free of f = 0 by intervals over its octants (zero_free.h). */
#include "core/octree/zero_free.h"

/* The octants reach this fraction of the node past its faces: a point the polygoniser
 * samples on a segment of the node (a + t (b - a)) may round an ulp or so past the box,
 * and must still lie in an octant. Far below any feature: 1e-9 of a cell. */
#define BOX_MARGIN 1e-9

/* The one sign of the corners when each lies beyond eps, else 0. */
static int corner_sign(const ism_corners *k, double eps)
{
    int sign = k->f[0] > eps ? 1 : k->f[0] < -eps ? -1 : 0;
    for (int c = 1; c < 8 && sign != 0; c++)
        if (!(sign > 0 ? k->f[c] > eps : k->f[c] < -eps))
            sign = 0;
    return sign;
}

bool ism_box_zero_free(const ism_tape *t, ism_eval_ws *ws, const double lo[3],
                       const double hi[3], const ism_corners *k, double eps,
                       uint64_t *intervals)
{
    int sign = corner_sign(k, eps);
    if (sign == 0)
        return false; /* a corner near 0 or corners of both signs: f = 0 may be in it */
    ism_interval part[3][8], out[8];
    for (int a = 0; a < 3; a++) {
        /* [lo, mid] and [mid, hi] cover the closed box whatever mid rounds to */
        double mid = 0.5 * (lo[a] + hi[a]), pad = BOX_MARGIN * (hi[a] - lo[a]);
        ism_interval low = {lo[a] - pad, mid}, high = {mid, hi[a] + pad};
        for (int o = 0; o < 8; o++)
            part[a][o] = (o >> a) & 1 ? high : low;
    }
    ism_eval_interval_batch(t, ws, part[0], part[1], part[2], out, 8);
    *intervals += 8;
    for (int o = 0; o < 8; o++)
        if (!(sign > 0 ? out[o].lo > eps : out[o].hi < -eps))
            return false;
    return true;
}
