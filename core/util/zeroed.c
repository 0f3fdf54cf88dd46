/* zeroed.c — zero-filled arrays written on a pool's threads (zeroed.h). */
#include "core/util/zeroed.h"
#include "core/util/cache_line.h"

#include <stdint.h>
#include <string.h>

/* Bytes each thread zeroes at least: below this one thread does all (waking the others
 * costs more than it saves). Shares are whole multiples of it, so two threads meet in one
 * page at most per boundary. */
#define ZERO_SHARE ((size_t)1 << 18)

typedef struct zero_job {
    unsigned char *p;
    size_t bytes, share;
} zero_job;

static void zero_share(void *ctx, size_t k, int thread)
{
    (void)thread;
    const zero_job *z = ctx;
    size_t lo = k * z->share, hi = lo + z->share < z->bytes ? lo + z->share : z->bytes;
    memset(z->p + lo, 0, hi - lo);
}

void *ism_zeroed_alloc(ism_pool *pool, size_t n, size_t size, ism_par_cost *cost)
{
    if (size && n > SIZE_MAX / size)
        return NULL;
    size_t bytes = n * size;
    unsigned char *p = ism_line_alloc(bytes);
    if (!p || bytes == 0)
        return p;
    size_t threads = (size_t)ism_pool_threads(pool);
    size_t share = (bytes + threads - 1) / threads;
    share = (share + ZERO_SHARE - 1) / ZERO_SHARE * ZERO_SHARE;
    zero_job z = {p, bytes, share};
    ism_pool_for(pool, (bytes + share - 1) / share, zero_share, &z, cost);
    return p;
}
