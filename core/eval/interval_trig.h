/* interval_trig.h — sin and cos over an interval, interval_ops.h's iv_sin / iv_cos bit for bit,
 * with the bounds' sines and cosines read from the workspace's memo of libm's pairs
 * (trig_pair.h's second table: what sin and cos return, bit for bit), so the gyroid's sin u
 * and cos u of one interval cost one sincos per bound, and a bound the memo holds none. For
 * the single-box pass (eval_interval.c); the batched pass takes the same memo pairs lane by
 * lane (eval_interval_batch.c's run_trig, interval_lanes.h's v_sin_at / v_cos_at).
 * glibc's documented error (at most 1 ulp) under iv_sin_at's widening by 4 ulp keeps the
 * bounds sound; the point evaluators' own pairs (sincos.h) have a measured bound, not a
 * proven one, so they are not used here. */
#ifndef ISM_INTERVAL_TRIG_H
#define ISM_INTERVAL_TRIG_H

#include "core/eval/interval_ops.h"
#include "core/eval/trig_pair.h"
#include "core/expr/tape.h"
#include <string.h>

/* op (ISM_OP_SIN or ISM_OP_COS) over a: from trig's interval entries (trig_pair.h) when one
 * holds a's bits, else both computed into the entry (a's bounds' libm pairs from the memo).
 * An entry holds what this computes for its interval, so a hit is a miss's bits. Called in
 * round-to-nearest only (libm and iv_sin_at's down4 / up4 assume it): an entry replays the
 * bits of the mode it was filled in. */
static inline ism_interval ism_iv_trig(int op, ism_interval a, ism_trig_cache *trig)
{
    if (!iv_trig_resolves(a))
        return iv(-1.0, 1.0);
    uint64_t lo, hi;
    memcpy(&lo, &a.lo, sizeof lo);
    memcpy(&hi, &a.hi, sizeof hi);
    uint64_t h = (lo * 0x9e3779b97f4a7c15ull) ^ (hi * 0xc2b2ae3d27d4eb4full);
    ism_trig_iv_entry *e = &trig->iv[h >> (64 - ISM_TRIG_IV_BITS)];
    if (e->lo != lo || e->hi != hi) {
        double s1, c1, s2, c2;
        ism_trig_pair_libm(trig, a.lo, &s1, &c1);
        ism_trig_pair_libm(trig, a.hi, &s2, &c2);
        *e = (ism_trig_iv_entry){lo, hi, iv_sin_at(a, s1, s2), iv_cos_at(a, c1, c2)};
    }
    return op == ISM_OP_SIN ? e->s : e->c;
}

#endif
