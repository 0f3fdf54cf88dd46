/* rm_memo.c — the point-keyed table of Newton measures (rm_memo.h): direct-mapped, the last
 * point measured in a slot evicts the one before. */
#include "core/remesh/rm_memo.h"

#include <stdlib.h>
#include <string.h>

/* Slots per vertex of the mesh: a vertex brings about two triangles' centroids, three edge
 * midpoints and itself into the measures, and the sweeps come back to them after a round. */
#define RM_MEMO_PER_VERTEX 4
/* Table sizes, as powers of two: the smallest covers a merge's trial and a ring's moves, the
 * largest (4.5 MB) the repeats of a round on the presets' meshes. */
#define RM_MEMO_MIN_BITS 10
#define RM_MEMO_MAX_BITS 16

rm_memo *rm_memo_new(size_t nverts)
{
    unsigned bits = RM_MEMO_MIN_BITS;
    while (bits < RM_MEMO_MAX_BITS && ((size_t)1 << bits) < RM_MEMO_PER_VERTEX * nverts)
        bits++;
    rm_memo *m = malloc(sizeof *m);
    if (m && !(m->e = calloc((size_t)1 << bits, sizeof *m->e))) {
        free(m);
        m = NULL;
    }
    if (m)
        m->bits = bits;
    return m;
}

void rm_memo_free(rm_memo *m)
{
    if (m)
        free(m->e);
    free(m);
}

rm_memo_entry *rm_memo_slot(rm_memo *m, const double x[3])
{
    uint64_t k[3];
    memcpy(k, x, sizeof k);
    uint64_t h = k[0] * 0x9e3779b97f4a7c15ull ^ k[1] * 0xc2b2ae3d27d4eb4full ^
                 k[2] * 0x165667b19e3779f9ull;
    h ^= h >> 31;
    rm_memo_entry *e = &m->e[(h * 0xd6e8feb86659fd93ull) >> (64 - m->bits)];
    if (e->state != RM_MEMO_EMPTY && memcmp(e->x, x, sizeof e->x) == 0)
        return e;
    memcpy(e->x, x, sizeof e->x);
    e->state = RM_MEMO_EMPTY;
    return e;
}
