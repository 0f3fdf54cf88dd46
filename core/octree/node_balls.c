/* node_balls.c — does a node meet a ball around a certified node finer than itself (see
 * node_balls.h)? */
#include "core/octree/node_balls.h"

#include <math.h>

bool ism_node_balls_split(const double (*ball)[ISM_NODE_BALL_FIELDS], size_t n,
                          const double lo[3], const double hi[3])
{
    double side = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    for (size_t i = 0; i < n; i++) {
        const double *b = ball[i];
        if (!(b[ISM_NODE_BALL_CELL] < side))
            continue;
        double d2 = 0; /* squared distance from the centre to the closed box */
        for (int a = 0; a < 3; a++) {
            double e = fmax(lo[a] - b[a], fmax(b[a] - hi[a], 0.0));
            d2 += e * e;
        }
        if (d2 <= b[ISM_NODE_BALL_R] * b[ISM_NODE_BALL_R])
            return true;
    }
    return false;
}
