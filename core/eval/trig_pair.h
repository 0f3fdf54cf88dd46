/* trig_pair.h — the sine and cosine of one argument, computed as a pair. Surfaces such as the
 * gyroid take both of the same argument (sin(k*x) … cos(k*x)), and the derivative of either
 * needs the other; sincos gives both for little more than the price of one. A memo of the
 * last few arguments, living for one evaluation, hands out the second of the pair. It is
 * keyed on the argument's bits, so a hit is exactly what a fresh call would return (and
 * glibc's sincos returns bit for bit what sin and cos return). Not public. */
#ifndef ISM_TRIG_PAIR_H
#define ISM_TRIG_PAIR_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#define ISM_TRIG_MEMO 4

typedef struct ism_trig_memo {
    uint64_t key[ISM_TRIG_MEMO];
    double s[ISM_TRIG_MEMO], c[ISM_TRIG_MEMO];
    unsigned n, next;
} ism_trig_memo;

static inline void ism_trig_pair(ism_trig_memo *m, double u, double *s, double *c)
{
    uint64_t key;
    memcpy(&key, &u, sizeof key);
    for (unsigned i = 0; i < m->n; i++)
        if (m->key[i] == key) {
            *s = m->s[i];
            *c = m->c[i];
            return;
        }
    sincos(u, s, c);
    unsigned slot = m->next;
    m->next = (slot + 1) % ISM_TRIG_MEMO;
    if (m->n < ISM_TRIG_MEMO)
        m->n++;
    m->key[slot] = key;
    m->s[slot] = *s;
    m->c[slot] = *c;
}

#endif
