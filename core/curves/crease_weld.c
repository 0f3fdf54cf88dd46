/* crease_weld.c — welding the copies of one crease point (crease_weld.h): the tie vertices
 * sorted by x, each compared with the earlier ones less than tol before it in x; a copy
 * takes the name of the first vertex of its point. */
#include "core/curves/crease_weld.h"
#include <stdlib.h>
#include "core/util/vec3.h"

typedef struct tie_at {
    double x;
    uint32_t v;
} tie_at;

static int by_x(const void *a, const void *b)
{
    const tie_at *p = a, *q = b;
    return p->x < q->x ? -1 : p->x > q->x ? 1 : (p->v > q->v) - (p->v < q->v);
}

size_t ism_crease_weld_ties(const ism_mesh *m, const uint32_t *label, uint32_t none, double tol,
                            uint32_t *tri, size_t nt)
{
    uint32_t *name = malloc((m->nverts ? m->nverts : 1) * sizeof *name);
    tie_at *ties = malloc((m->nverts ? m->nverts : 1) * sizeof *ties);
    if (!name || !ties) {
        free(name);
        free(ties);
        return SIZE_MAX;
    }
    size_t n = 0, renamed = 0;
    for (size_t v = 0; v < m->nverts; v++)
        name[v] = (uint32_t)v;
    for (size_t i = 0; i < 3 * nt; i++) {
        uint32_t v = tri[i];
        if (label[v] == none && name[v] == v) {
            name[v] = none; /* listed once */
            ties[n++] = (tie_at){m->pos[3 * (size_t)v], v};
        }
    }
    for (size_t i = 0; i < n; i++)
        name[ties[i].v] = ties[i].v;
    qsort(ties, n, sizeof *ties, by_x);
    for (size_t i = 1; i < n; i++) {
        const double *p = m->pos + 3 * (size_t)ties[i].v;
        for (size_t j = i; j-- > 0 && p[0] - ties[j].x <= tol;)
            if (ism_sqdist3(p, m->pos + 3 * (size_t)ties[j].v) <= tol * tol) {
                name[ties[i].v] = name[ties[j].v];
                renamed++;
                break;
            }
    }
    for (size_t i = 0; renamed && i < 3 * nt; i++)
        tri[i] = name[tri[i]];
    free(name);
    free(ties);
    return renamed;
}
