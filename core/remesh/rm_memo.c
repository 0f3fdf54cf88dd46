/* rm_memo.c — the point-keyed table of Newton measures (rm_memo.h): direct-mapped, the last
 * point measured in a slot evicts the one before. */
#include "core/remesh/rm_memo.h"

#include <stdlib.h>
#include <string.h>

/* Slots, as a power of two: 2^10 (96 KB with ∇f kept) stays in the L2 cache. Most repeats
 * come within a merge's verdict and trial, a few hundred points apart; a table sized to
 * catch the sweep's repeats too (4 slots a vertex) made every lookup a cache miss — min CPU
 * of 3-4 alternating runs, bench_error mesh S 3e-3 10, simplification ms at 2^10 / 2^12 /
 * 2^14 / no table: sphere 47.5 / 58.2 / 77.4 / 51.4, torus 222 / 221 / 287 / 211,
 * gyroid-ball 1091 / 1361 / — / 1312 (2^11: 1232). */
#define RM_MEMO_BITS 10

/* Every slot empty: its state alone, which every reader asks first (rm_memo_holds, and the
 * measures filling a claimed slot); a point is written with its first measure. calloc cleared
 * all 96 KB, a fixed cost beside a small mesh's pass: ellipsoid own box, callgrind
 * --quality good --threads 1, 98.7k of ism_quality_pass's 6.17M (callgrind counts the
 * memset's rep stosb a byte an instruction, so the time spared is smaller than that). */
rm_memo *rm_memo_new(void)
{
    rm_memo *m = malloc(sizeof *m);
    if (m && !(m->e = malloc(((size_t)1 << RM_MEMO_BITS) * sizeof *m->e))) {
        free(m);
        m = NULL;
    }
    if (!m)
        return NULL;
    m->bits = RM_MEMO_BITS;
    for (size_t i = 0; i < (size_t)1 << RM_MEMO_BITS; i++)
        m->e[i].state = RM_MEMO_EMPTY;
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
    return rm_memo_claim(rm_memo_peek(m, x), x);
}
