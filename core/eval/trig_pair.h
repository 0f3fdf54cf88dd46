/* trig_pair.h — the sine and cosine of one argument, computed as a pair. Surfaces such as the
 * gyroid take both of the same argument (sin(k*x) … cos(k*x)), and the derivative of either
 * needs the other; sincos gives both for little more than the price of one. A memo of
 * arguments, kept by the workspace, hands out the second of the pair and repeats. It is
 * keyed on the argument's bits, so a hit is exactly what a fresh call would return (and
 * glibc's sincos returns bit for bit what sin and cos return). Not public. */
#ifndef ISM_TRIG_PAIR_H
#define ISM_TRIG_PAIR_H

#include <math.h>
#include <stdint.h>
#include <string.h>

/* A direct-mapped cache of 2^ISM_TRIG_CACHE_BITS arguments, kept by the workspace from one
 * evaluation to the next: the polygoniser evaluates f along lattice edges and faces, where
 * two of the three coordinates stay the same from point to point (sin(k*x) repeats), and
 * corners shared by neighbours. 512 entries (12 KB, beside the workspace's 40 KB of batch
 * registers) take most repeats on the gyroid. Every entry starts as the pair of +0.0, which
 * is what sincos gives there, so no entry is ever invalid. */
#define ISM_TRIG_CACHE_BITS 9

typedef struct ism_trig_entry {
    uint64_t key;
    double s, c;
} ism_trig_entry;

typedef struct ism_trig_cache {
    ism_trig_entry e[1u << ISM_TRIG_CACHE_BITS];
} ism_trig_cache;

static inline void ism_trig_cache_init(ism_trig_cache *m)
{
    for (unsigned i = 0; i < (1u << ISM_TRIG_CACHE_BITS); i++)
        m->e[i] = (ism_trig_entry){0, 0.0, 1.0}; /* sincos(+0.0) */
}

static inline void ism_trig_pair(ism_trig_cache *m, double u, double *s, double *c)
{
    uint64_t key;
    memcpy(&key, &u, sizeof key);
    ism_trig_entry *e = &m->e[(key * 0x9e3779b97f4a7c15ull) >> (64 - ISM_TRIG_CACHE_BITS)];
    if (e->key != key) {
        sincos(u, &e->s, &e->c);
        e->key = key;
    }
    *s = e->s;
    *c = e->c;
}

#endif
