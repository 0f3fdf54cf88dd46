/* test_select.c — the k-th smallest on a pool's threads (core/analysis/select.h): the radix
 * selection on 2 and 4 threads returns, bit for bit, element k of a sorted copy (qsort, the
 * independent answer), for doubles and floats spread over many octaves, with negatives,
 * with heavy ties (every candidate left in one bucket down to the last digit), all equal, and
 * at the ranks the analysis asks for (0, the median, the 99th percentile, the last); and the
 * pair of elements k-1 and k (the even-length median) on 1, 2 and 4 threads. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/analysis/select.h"

/* Above the serial cut-off (select.c's SELECT_SERIAL) several times, several blocks. */
enum { N = 200003 };

static uint64_t rng = 0x9e3779b97f4a7c15ull;
static double uniform(void) /* xorshift64*, in [0, 1) */
{
    rng ^= rng >> 12;
    rng ^= rng << 25;
    rng ^= rng >> 27;
    return (double)((rng * 0x2545f4914f6cdd1dull) >> 11) / 9007199254740992.0;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* The data sets: kind 0 distances over 12 octaves, 1 signed values, 2 five values repeated,
 * 3 all equal, 4 values one ulp apart around 1 (one bucket down to the last digit). */
static double value(int kind, size_t i)
{
    switch (kind) {
    case 0: return exp2(-12 * uniform()) * uniform();
    case 1: return (uniform() - 0.4) * 1e3;
    case 2: return (double)(i * 7 % 5) * 0.25;
    case 3: return 0.125;
    default: return nextafter(1.0, 2.0) + (double)(i % 3) * 2.220446049250313e-16;
    }
}

static void check_kind(int kind, ism_pool *pool, int threads)
{
    double *v = malloc(N * sizeof *v), *sorted = malloc(N * sizeof *sorted);
    float *vf = malloc(N * sizeof *vf), *sortedf = malloc(N * sizeof *sortedf);
    cr_assert(v && sorted && vf && sortedf);
    for (size_t i = 0; i < N; i++) {
        v[i] = sorted[i] = value(kind, i);
        vf[i] = sortedf[i] = (float)v[i];
    }
    qsort(sorted, N, sizeof *sorted, cmp_double);
    qsort(sortedf, N, sizeof *sortedf, cmp_float);
    const size_t ranks[] = {0, 1, N / 2, (size_t)(0.99 * (N - 1)), N - 2, N - 1};
    for (size_t r = 0; r < sizeof ranks / sizeof *ranks; r++) {
        size_t k = ranks[r];
        double d = ism_an_select_double_on(pool, v, N, k);
        float f = ism_an_select_float_on(pool, vf, N, k);
        cr_expect(memcmp(&d, &sorted[k], sizeof d) == 0, "kind %d, %d threads, k %zu: %.17g, "
                  "sorted %.17g", kind, threads, k, d, sorted[k]);
        cr_expect(memcmp(&f, &sortedf[k], sizeof f) == 0, "kind %d, %d threads, k %zu (float): "
                  "%.9g, sorted %.9g", kind, threads, k, (double)f, (double)sortedf[k]);
    }
    free(v);
    free(sorted);
    free(vf);
    free(sortedf);
}

Test(select, radix_on_threads_is_the_sorted_element)
{
    for (int threads = 1; threads <= 4; threads *= 2) {
        ism_pool *pool = threads > 1 ? ism_pool_new(threads) : NULL;
        for (int kind = 0; kind < 5; kind++)
            check_kind(kind, pool, threads);
        ism_pool_free(pool);
    }
}

/* The pair (elements k-1 and k, the even-length median's two) against the sorted copy, for n
 * above the serial cut-off and below it (where the threads fall back to the quickselect). */
static void check_pair(int kind, ism_pool *pool, int threads, size_t n)
{
    float *vf = malloc(n * sizeof *vf), *sortedf = malloc(n * sizeof *sortedf);
    cr_assert(vf && sortedf);
    for (size_t i = 0; i < n; i++)
        vf[i] = sortedf[i] = (float)value(kind, i);
    qsort(sortedf, n, sizeof *sortedf, cmp_float);
    const size_t ranks[] = {1, n / 2, (size_t)(0.99 * (double)(n - 1)), n - 1};
    for (size_t r = 0; r < sizeof ranks / sizeof *ranks; r++) {
        size_t k = ranks[r];
        float below = -1;
        float at = ism_an_select_float_pair_on(pool, vf, n, k, &below);
        cr_expect(memcmp(&at, &sortedf[k], sizeof at) == 0 &&
                      memcmp(&below, &sortedf[k - 1], sizeof below) == 0,
                  "kind %d, %d threads, n %zu, k %zu: %.9g %.9g, sorted %.9g %.9g", kind,
                  threads, n, k, (double)below, (double)at, (double)sortedf[k - 1],
                  (double)sortedf[k]);
    }
    free(vf);
    free(sortedf);
}

Test(select, pair_is_the_sorted_elements_k_minus_1_and_k)
{
    for (int threads = 1; threads <= 4; threads *= 2) {
        ism_pool *pool = threads > 1 ? ism_pool_new(threads) : NULL;
        for (int kind = 0; kind < 5; kind++) {
            check_pair(kind, pool, threads, N - 1);
            check_pair(kind, pool, threads, 1000);
        }
        ism_pool_free(pool);
    }
}
