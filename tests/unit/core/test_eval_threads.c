/* test_eval_threads.c — one immutable tape shared by several threads, each with its own
 * workspace (and its own shortened tapes): every thread computes exactly what a single
 * thread computed beforehand. */
#include <criterion/criterion.h>
#include <pthread.h>
#include <string.h>

#include "test_eval_surfaces.h"

enum { NTHREADS = 4, NPTS = 2000, ROUNDS = 20 };

typedef struct shared {
    const ism_tape *tape;
    double x[NPTS], y[NPTS], z[NPTS];
    double want_f[NPTS], want_g[NPTS][3];
    ism_interval want_iv[NPTS / 10];
} shared;

typedef struct job {
    const shared *s;
    int mismatches;
} job;

static ism_interval box_of(const shared *s, int i)
{
    (void)s;
    double lo = -1.5 + 3.0 * i / (NPTS / 10);
    return (ism_interval){ lo, lo + 0.2 };
}

static void *worker(void *arg)
{
    job *j = arg;
    const shared *s = j->s;
    ism_eval_ws *ws = ism_eval_ws_new(s->tape);
    ism_tape *shorter = ism_tape_new_like(s->tape);
    static _Thread_local double out[NPTS];
    for (int round = 0; round < ROUNDS && ws && shorter; round++) {
        ism_eval_batch(s->tape, ws, s->x, s->y, s->z, out, NPTS);
        for (int i = 0; i < NPTS; i++) {
            double g[3];
            j->mismatches += out[i] != s->want_f[i];
            j->mismatches += ism_eval_gradient(s->tape, ws, s->x[i], s->y[i], s->z[i], g)
                             != s->want_f[i];
            j->mismatches += memcmp(g, s->want_g[i], sizeof g) != 0;
        }
        for (int b = 0; b < NPTS / 10; b++) {
            ism_interval bx = box_of(s, b), r;
            const ism_tape *use = ism_tape_shorten(s->tape, ws, bx, bx, bx, shorter, &r)
                                  ? shorter : s->tape;
            j->mismatches += r.lo != s->want_iv[b].lo || r.hi != s->want_iv[b].hi;
            double p = 0.5 * (bx.lo + bx.hi);
            j->mismatches += ism_eval_point(use, ws, p, p, p)
                             != ism_eval_point(s->tape, ws, p, p, p);
        }
    }
    ism_tape_free(shorter);
    ism_eval_ws_free(ws);
    return NULL;
}

Test(eval_threads, shared_tape_private_workspaces)
{
    static shared s;
    s.tape = test_surface_compile(&TEST_SURFACES[3]); /* the gyroid ball: sin, cos, max */
    ism_eval_ws *ws = ism_eval_ws_new(s.tape);
    test_rng rng = { 3 };
    for (int i = 0; i < NPTS; i++) {
        s.x[i] = test_uniform(&rng, -1.5, 1.5);
        s.y[i] = test_uniform(&rng, -1.5, 1.5);
        s.z[i] = test_uniform(&rng, -1.5, 1.5);
        s.want_f[i] = ism_eval_gradient(s.tape, ws, s.x[i], s.y[i], s.z[i], s.want_g[i]);
    }
    for (int b = 0; b < NPTS / 10; b++) {
        ism_interval bx = box_of(&s, b);
        s.want_iv[b] = ism_eval_interval(s.tape, ws, bx, bx, bx);
    }
    ism_eval_ws_free(ws);
    pthread_t th[NTHREADS];
    job jobs[NTHREADS];
    for (int k = 0; k < NTHREADS; k++) {
        jobs[k] = (job){ &s, 0 };
        cr_assert_eq(pthread_create(&th[k], NULL, worker, &jobs[k]), 0);
    }
    for (int k = 0; k < NTHREADS; k++) {
        pthread_join(th[k], NULL);
        cr_expect_eq(jobs[k].mismatches, 0, "thread %d: %d mismatches", k, jobs[k].mismatches);
    }
    ism_tape_free((ism_tape *)s.tape);
}
