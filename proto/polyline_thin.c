/* polyline_thin.c — Douglas-Peucker over a mesh polyline's vertices (polyline_thin.h), with an
 * explicit stack (a chain of a CSG preset's crease has thousands of vertices: no recursion
 * depth that grows with it). */
#include "proto/polyline_thin.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

size_t ism_polyline_thin(const double *pos, const uint32_t *idx, size_t n, double tol,
                         uint8_t *keep)
{
    if (!n)
        return 0;
    if (!(tol > 0) || n <= 2) {
        memset(keep, 1, n);
        return n;
    }
    /* each pushed span is split at a vertex that is then kept: at most n - 2 splits, two
     * spans each, plus the first */
    size_t cap = 2 * n, top = 0, kept = 2;
    size_t *stack = malloc(cap * sizeof *stack);
/* vertex i's position; idx NULL: the identity */
#define AT(i) (pos + 3 * (size_t)(idx ? idx[i] : (uint32_t)(i)))
    if (!stack)
        return 0;
    memset(keep, 0, n);
    keep[0] = keep[n - 1] = 1;
    stack[top++] = 0;
    stack[top++] = n - 1;
    while (top) {
        size_t b = stack[--top], a = stack[--top];
        if (b <= a + 1)
            continue;
        const double *pa = AT(a), *pb = AT(b);
        /* a closed chain's first span has a = b in space: its farthest vertex is kept
         * whatever tol says, so that the printed chain is a loop and not a point */
        bool loop = idx && a == 0 && b == n - 1 && idx[a] == idx[b];
        double far = -1;
        size_t at = a + 1;
        for (size_t i = a + 1; i < b; i++) {
            double d = sqrt(ism_sqdist_segment3(AT(i), pa, pb));
            if (d > far) {
                far = d;
                at = i;
            }
        }
        if (far > tol || loop) {
            keep[at] = 1;
            kept++;
            stack[top++] = a;
            stack[top++] = at;
            stack[top++] = at;
            stack[top++] = b;
        }
    }
    free(stack);
    return kept;
#undef AT
}
