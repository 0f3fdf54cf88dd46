/* sheet_field.c — lattice vertices with f, ∇f and the Hessian's dominant eigenpair (see
 * sheet_field.h): a key map gives each lattice point a dense index; evaluations are batched
 * into chunks handed to threads, each with its own workspace. */
#include "core/singular/sheet_field.h"
#include "core/singular/lattice_key.h"
#include "core/util/clock.h"
#include "core/util/parallel.h"
#include "core/util/sym3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Vertices per task of a parallel evaluation: large enough to amortise a task, small
 * enough to balance two to eight threads. */
#define SF_CHUNK 256
/* A private bit of ism_sheet_vertex.have: listed for the evaluation under way. */
#define SF_QUEUED 0x80

bool ism_sheet_field_init(ism_sheet_field *sf, const ism_tape *f, const ism_grid *g, int threads)
{
    memset(sf, 0, sizeof *sf);
    sf->f = f;
    sf->grid = g;
    sf->threads = threads < 1 ? 1 : threads;
    atomic_init(&sf->stopped, 0);
    ism_key_map_init(&sf->map);
    sf->ws = calloc((size_t)sf->threads, sizeof *sf->ws);
    if (!sf->ws)
        return false;
    for (int i = 0; i < sf->threads; i++)
        if (!(sf->ws[i] = ism_eval_ws_new(f))) {
            ism_sheet_field_free(sf);
            return false;
        }
    return true;
}

void ism_sheet_field_free(ism_sheet_field *sf)
{
    for (int i = 0; sf->ws && i < sf->threads; i++)
        ism_eval_ws_free(sf->ws[i]);
    free(sf->ws);
    ism_key_map_free(&sf->map);
    free(sf->v);
    memset(sf, 0, sizeof *sf);
}

bool ism_sheet_field_should_stop(ism_sheet_field *sf)
{
    if (atomic_load(&sf->stopped))
        return true;
    if ((sf->cancel && *sf->cancel) || (sf->deadline_ms > 0 && ism_now_ms() > sf->deadline_ms)) {
        atomic_store(&sf->stopped, 1);
        return true;
    }
    return false;
}

uint32_t ism_sheet_field_vertex(ism_sheet_field *sf, uint64_t key)
{
    bool added;
    uint32_t i = ism_key_map_add(&sf->map, key, &added);
    if (i == ISM_KEY_NONE || !added)
        return i;
    if (i >= sf->cap) {
        size_t c = sf->cap ? 2 * sf->cap : 4096;
        ism_sheet_vertex *v = realloc(sf->v, c * sizeof *v);
        if (!v)
            return ISM_KEY_NONE; /* the key stays mapped; a later call fails the same way */
        sf->v = v;
        sf->cap = c;
    }
    memset(&sf->v[i], 0, sizeof sf->v[i]);
    int32_t ip[3];
    ism_lkey_unpack(key, ip);
    for (int a = 0; a < 3; a++)
        sf->v[i].p[a] = ism_grid_coord(sf->grid, a, ip[a]);
    return i;
}

bool ism_sheet_dominant(const double h[6], double n[3], double *lam)
{
    double eig[3], vec[3][3];
    ism_sym3_eigen(h, eig, vec);
    int k = fabs(eig[0]) > fabs(eig[2]) ? 0 : 2; /* ascending: the extremes are the largest */
    if (!(fabs(eig[k]) > 0) || !isfinite(eig[k]))
        return false;
    memcpy(n, vec[k], sizeof vec[k]);
    *lam = eig[k];
    return true;
}

typedef struct need_job {
    ism_sheet_field *sf;
    const uint32_t *todo;
    size_t n;
    int what;
} need_job;

typedef struct jet_job {
    ism_sheet_field *sf;
    const uint32_t *todo;
    size_t n;
} jet_job;

static void jet_task(void *ctx, size_t task, int thread)
{
    jet_job *j = ctx;
    ism_sheet_field *sf = j->sf;
    size_t end = (task + 1) * SF_CHUNK < j->n ? (task + 1) * SF_CHUNK : j->n;
    double h[6];
    if (ism_sheet_field_should_stop(sf))
        return;
    for (size_t i = task * SF_CHUNK; i < end; i++) {
        ism_sheet_vertex *v = &sf->v[j->todo[i]];
        v->f = ism_eval_hessian(sf->f, sf->ws[thread], v->p[0], v->p[1], v->p[2], v->g, h);
        v->have |= ISM_SF_JET;
        if (!ism_sheet_dominant(h, v->n, &v->lam))
            v->have |= ISM_SF_NO_DIR;
    }
}

bool ism_sheet_field_jets(ism_sheet_field *sf, const uint32_t *idx, size_t n)
{
    uint32_t *todo = malloc((n ? n : 1) * sizeof *todo);
    if (!todo)
        return false;
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        ism_sheet_vertex *v = &sf->v[idx[i]];
        if (v->have & (ISM_SF_JET | SF_QUEUED))
            continue;
        v->have |= SF_QUEUED; /* a vertex listed twice is evaluated once */
        todo[m++] = idx[i];
    }
    for (size_t i = 0; i < m; i++)
        sf->v[todo[i]].have &= (uint8_t)~SF_QUEUED;
    jet_job j = {sf, todo, m};
    ism_parallel_for(sf->threads, (m + SF_CHUNK - 1) / SF_CHUNK, jet_task, &j);
    sf->evals_jet += m;
    free(todo);
    return true;
}
