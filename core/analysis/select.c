/* select.c — the k-th smallest of an array in expected linear time (quickselect with a
 * median-of-three pivot and a three-way partition, so runs of equal values cost nothing),
 * for medians of angles and gradient norms; and the same value found on a pool's threads by
 * a radix selection (the analysis's percentiles and medians). Deterministic: no random
 * pivots. Callers pass finite values only. */
#include "core/analysis/select.h"
#include "core/util/parallel.h"

#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define DEFINE_SELECT(name, T)                                                  \
    T name(T *v, size_t n, size_t k)                                            \
    {                                                                           \
        size_t lo = 0, hi = n - 1;                                              \
        while (lo < hi) {                                                       \
            T a = v[lo], b = v[lo + (hi - lo) / 2], c = v[hi];                  \
            T pivot = a < b ? (b < c ? b : (a < c ? c : a))                     \
                            : (a < c ? a : (b < c ? c : b));                    \
            size_t lt = lo, i = lo, gt = hi;                                    \
            while (i <= gt) {                                                   \
                T x = v[i];                                                     \
                if (x < pivot) {                                                \
                    v[i++] = v[lt];                                             \
                    v[lt++] = x;                                                \
                } else if (x > pivot) {                                         \
                    v[i] = v[gt];                                               \
                    v[gt--] = x;                                                \
                } else {                                                        \
                    i++;                                                        \
                }                                                               \
            }                                                                   \
            if (k < lt)                                                         \
                hi = lt - 1;                                                    \
            else if (k > gt)                                                    \
                lo = gt + 1;                                                    \
            else                                                                \
                return pivot;                                                   \
        }                                                                       \
        return v[k];                                                            \
    }

DEFINE_SELECT(ism_an_select_double, double)
DEFINE_SELECT(ism_an_select_float, float)
static DEFINE_SELECT(select_key, uint64_t)

/* The radix selection: each pass counts the items' next digit of their order key (per block
 * of SELECT_BLOCK items, on the pool), finds the bucket holding the k-th, and copies that
 * bucket's keys out (each block at its own offset) for the next pass; a few thousand left
 * are finished by select_key. Digits of 12 bits: for doubles the first pass splits by sign
 * and exponent (distances and norms spread over octaves), the second by 12 bits of mantissa —
 * a bucket of 1/4096 of an octave, left with a few items; for floats the first takes sign,
 * exponent and 3 mantissa bits, and the third (shift FLOAT_LAST_SHIFT) the last of their 32.
 * A block is tens of microseconds. */
#define SELECT_BLOCK 32768
#define DIGIT_BITS 12
#define BUCKETS (1u << DIGIT_BITS)
/* Up to this many items (or items left after a pass) the quickselect runs on the calling
 * thread: under a millisecond, less than the passes' hand-offs would save. */
#define SELECT_SERIAL 16384
/* A float's key is the upper 32 bits: the passes at shifts 52, 40 and 28 cover bits 28..63,
 * so after the one at 28 every float bit is decided and further passes would only count
 * ties; a double's key needs the passes down to shift 0. */
#define FLOAT_LAST_SHIFT (64 - 3 * DIGIT_BITS)

/* Order keys: unsigned integers ordered as the values are (IEEE bits; negative values
 * inverted, positive ones with the sign bit set), floats in the upper 32 bits. */
static uint64_t key_of_double(double x)
{
    uint64_t b;
    memcpy(&b, &x, sizeof b);
    return b >> 63 ? ~b : b | (1ull << 63);
}

static double double_of_key(uint64_t k)
{
    uint64_t b = k >> 63 ? k & ~(1ull << 63) : ~k;
    double x;
    memcpy(&x, &b, sizeof x);
    return x;
}

static uint64_t key_of_float(float x)
{
    uint32_t b;
    memcpy(&b, &x, sizeof b);
    return (uint64_t)(b >> 31 ? ~b : b | (1u << 31)) << 32;
}

static float float_of_key(uint64_t k)
{
    uint32_t h = (uint32_t)(k >> 32), b = h >> 31 ? h & ~(1u << 31) : ~h;
    float x;
    memcpy(&x, &b, sizeof x);
    return x;
}

typedef struct radix {
    const double *vd;    /* the first pass's items: doubles, */
    const float *vf;     /* or floats, */
    const uint64_t *src; /* or, after it, the keys left */
    uint64_t *dst;       /* where the chosen bucket's keys go */
    size_t n;            /* items in this pass */
    int shift;           /* the digit: key >> shift, DIGIT_BITS of it */
    int last_shift;      /* the lowest shift that still decides bits: FLOAT_LAST_SHIFT or 0 */
    uint32_t *hist;      /* per block, BUCKETS counts */
    size_t *at;          /* per block, where its chosen keys go */
    uint32_t chosen;
} radix;

static uint64_t key_at(const radix *r, size_t i)
{
    return r->src ? r->src[i] : r->vd ? key_of_double(r->vd[i]) : key_of_float(r->vf[i]);
}

static uint32_t digit(const radix *r, uint64_t key)
{
    return (uint32_t)(key >> r->shift) & (BUCKETS - 1);
}

static void count_block(void *ctx, size_t blk, int thread)
{
    (void)thread;
    radix *r = ctx;
    uint32_t *h = r->hist + blk * BUCKETS;
    memset(h, 0, BUCKETS * sizeof *h);
    for (size_t i = blk * SELECT_BLOCK, end = ism_block_end(blk, SELECT_BLOCK, r->n); i < end;
         i++)
        h[digit(r, key_at(r, i))]++;
}

static void gather_block(void *ctx, size_t blk, int thread)
{
    (void)thread;
    radix *r = ctx;
    size_t o = r->at[blk];
    for (size_t i = blk * SELECT_BLOCK, end = ism_block_end(blk, SELECT_BLOCK, r->n); i < end;
         i++) {
        uint64_t key = key_at(r, i);
        if (digit(r, key) == r->chosen)
            r->dst[o++] = key;
    }
}

/* The bucket holding the k-th item of this pass; *k becomes its rank inside the bucket,
 * r->at each block's offset into it; returns its size. */
static size_t choose_bucket(radix *r, size_t nblocks, size_t *k)
{
    size_t below = 0;
    for (uint32_t b = 0; b < BUCKETS; b++) {
        size_t c = 0;
        for (size_t blk = 0; blk < nblocks; blk++) {
            r->at[blk] = c;
            c += r->hist[blk * BUCKETS + b];
        }
        if (below + c > *k) {
            r->chosen = b;
            *k -= below;
            return c;
        }
        below += c;
    }
    return 0; /* not reached: the counts add up to n > k */
}

/* The k-th smallest key of the items in r (the first pass's values); false when out of
 * memory (nothing was changed). */
static bool radix_select(ism_pool *pool, radix *r, size_t k, uint64_t *out)
{
    size_t nblocks = ism_blocks(r->n, SELECT_BLOCK);
    r->hist = malloc(nblocks * BUCKETS * sizeof *r->hist);
    r->at = malloc(nblocks * sizeof *r->at);
    uint64_t *owned = NULL; /* r->src once it is ours */
    bool ok = r->hist && r->at;
    r->shift = 64 - DIGIT_BITS;
    while (ok) {
        size_t nb = ism_blocks(r->n, SELECT_BLOCK);
        ism_pool_for(pool, nb, count_block, r, NULL);
        size_t in = choose_bucket(r, nb, &k);
        if (in < r->n || !r->src) { /* the bucket's keys, for the next pass */
            if (!(r->dst = malloc((in ? in : 1) * sizeof *r->dst))) {
                ok = false;
                break;
            }
            ism_pool_for(pool, nb, gather_block, r, NULL);
            free(owned);
            r->src = owned = r->dst;
            r->n = in;
        }
        if (r->n <= SELECT_SERIAL || r->shift <= r->last_shift)
            break;
        /* the digits may overlap bits already equal in every key left: harmless */
        r->shift = r->shift > DIGIT_BITS ? r->shift - DIGIT_BITS : 0;
    }
    if (ok)
        *out = select_key(owned, r->n, k);
    free(owned);
    free(r->hist);
    free(r->at);
    return ok;
}

/* Whether the radix selection on pool is worth it for n items. */
static bool on_threads(ism_pool *pool, size_t n)
{
    return ism_pool_threads(pool) > 1 && n > SELECT_SERIAL;
}

double ism_an_select_double_on(ism_pool *pool, double *v, size_t n, size_t k)
{
    radix r = {.vd = v, .n = n};
    uint64_t key;
    if (on_threads(pool, n) && radix_select(pool, &r, k, &key))
        return double_of_key(key);
    return ism_an_select_double(v, n, k);
}

float ism_an_select_float_on(ism_pool *pool, float *v, size_t n, size_t k)
{
    radix r = {.vf = v, .n = n, .last_shift = FLOAT_LAST_SHIFT};
    uint64_t key;
    if (on_threads(pool, n) && radix_select(pool, &r, k, &key))
        return float_of_key(key);
    return ism_an_select_float(v, n, k);
}

float ism_an_select_float_pair_on(ism_pool *pool, float *v, size_t n, size_t k, float *below)
{
    radix r = {.vf = v, .n = n, .last_shift = FLOAT_LAST_SHIFT};
    radix r_below = r;
    uint64_t key, key_below;
    if (on_threads(pool, n) && radix_select(pool, &r, k, &key) &&
        radix_select(pool, &r_below, k - 1, &key_below)) {
        *below = float_of_key(key_below);
        return float_of_key(key);
    }
    float at = ism_an_select_float(v, n, k);
    float lower = v[0]; /* the quickselect left v[0 .. k) all <= at: element k-1 is their max */
    for (size_t i = 1; i < k; i++)
        if (v[i] > lower)
            lower = v[i];
    *below = lower;
    return at;
}
