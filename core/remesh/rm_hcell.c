/* rm_hcell.c — the grid of Hessian bounds (rm_hcell.h): cells keyed by their integer
 * coordinates (a lattice key, lattice_key.h) in a key map (key_map.h) whose indices address
 * the bounds, each cell's bound worked out from f's interval jet the first time a point in it
 * asks. */
#include "core/remesh/rm_hcell.h"
#include "core/eval/interval_jet.h"
#include "core/singular/key_map.h"
#include "core/singular/lattice_key.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Cell coordinates are offset by half a lattice key's range per axis (out of range: not
 * asked). */
#define HC_HALF (1 << (ISM_LKEY_BITS - 1))
/* A key no cell has (a lattice key uses 63 bits). */
#define HC_EMPTY UINT64_MAX

struct rm_hcell {
    double lo[3], side, inv_side;
    uint64_t last_key;   /* the cell asked last and its bound: consecutive points of a fan */
    double last_m;       /* mostly share a cell (HC_EMPTY: none yet) */
    ism_key_map cells;   /* cell key -> index into m */
    double *m;           /* by index: the Hessian bound of the cell (INFINITY: none) */
    size_t mcap;         /* m's length */
    size_t worked, asked, spared; /* cells whose jet was worked out; points asked of a
                                     cell's bound, and those it spared a second step */
    bool stopped;        /* no new cell is worked out (rm_hcell.h's trial) */
    ism_ivjet_ws *jws;
};

struct rm_hcell *rm_hcell_new(const rm_pass *p)
{
    const ism_mesh *m = p->r.m;
    double sum = 0, lo[3] = {INFINITY, INFINITY, INFINITY};
    size_t n = 0;
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *v = m->tri + 3 * t;
        for (int k = 0; k < 3; k++)
            sum += rm_dist(m->pos + 3 * (size_t)v[k], m->pos + 3 * (size_t)v[(k + 1) % 3]), n++;
    }
    for (size_t v = 0; v < m->nverts; v++)
        for (int k = 0; k < 3; k++)
            lo[k] = fmin(lo[k], m->pos[3 * v + k]);
    double side = n ? RM_HCELL_EDGES * sum / (double)n : 0;
    if (!(side > 0) || !isfinite(side) || !isfinite(lo[0] + lo[1] + lo[2]))
        return NULL;
    struct rm_hcell *h = calloc(1, sizeof *h);
    if (!h)
        return NULL;
    ism_key_map_init(&h->cells);
    h->jws = ism_ivjet_ws_new(p->f);
    if (!h->jws) {
        rm_hcell_free(h);
        return NULL;
    }
    memcpy(h->lo, lo, sizeof lo);
    h->side = side;
    h->inv_side = 1 / side;
    h->last_key = HC_EMPTY;
    return h;
}

void rm_hcell_free(struct rm_hcell *h)
{
    if (!h)
        return;
    ism_key_map_free(&h->cells);
    free(h->m);
    ism_ivjet_ws_free(h->jws);
    free(h);
}

/* ‖H‖_F over the cell c (integer coordinates) grown by grow each way, from the Hessian's
 * enclosures; INFINITY where the jet has a kink or an unbounded entry. */
static double cell_bound(const rm_pass *p, struct rm_hcell *h, const int64_t c[3], double grow)
{
    ism_interval b[3];
    for (int k = 0; k < 3; k++) {
        b[k].lo = h->lo[k] + (double)c[k] * h->side - grow;
        b[k].hi = h->lo[k] + (double)(c[k] + 1) * h->side + grow;
    }
    ism_ivjet j;
    if (ism_eval_interval_jet(p->f, h->jws, b, NULL, NULL, &j) != 0)
        return INFINITY; /* a kink, or the workspace does not fit ((size_t)-1) */
    double h2 = 0;
    for (int k = 0; k < 6; k++) { /* xx xy xz yy yz zz: the mixed ones twice in ‖H‖_F */
        double most = fmax(fabs(j.h[k].lo), fabs(j.h[k].hi));
        h2 += (k == 1 || k == 2 || k == 4 ? 2 : 1) * most * most;
    }
    /* the few roundings of the sums and the root: far under the margin's relative 2^-40 */
    double m = sqrt(h2) * (1 + 0x1p-40);
    return m >= 0 && isfinite(m) ? m : INFINITY; /* NaN: none */
}

/* Room in m for one more cell; false when out of memory (m is as it was). */
static bool room(struct rm_hcell *h)
{
    if (h->cells.n < h->mcap)
        return true;
    size_t cap = h->mcap ? 2 * h->mcap : 256; /* four trials of cells (rm_hcell.h) */
    double *m = realloc(h->m, cap * sizeof *m);
    if (!m)
        return false;
    h->m = m;
    h->mcap = cap;
    return true;
}

/* The Hessian bound of x's cell: known, or worked out now (unless the trial stopped new
 * ones, or out of memory: INFINITY). */
static double bound_at(rm_pass *p, struct rm_hcell *h, const double x[3])
{
    int64_t c[3];
    for (int k = 0; k < 3; k++) {
        /* shifted by half the range before the truncation: a floor for every cell kept */
        double q = (x[k] - h->lo[k]) * h->inv_side + HC_HALF;
        if (!(q >= 0 && q < 2.0 * HC_HALF))
            return INFINITY;
        c[k] = (int64_t)q - HC_HALF;
    }
    uint64_t key = ism_lkey((int32_t)(c[0] + HC_HALF), (int32_t)(c[1] + HC_HALF),
                            (int32_t)(c[2] + HC_HALF));
    if (key == h->last_key)
        return h->last_m;
    uint32_t i = ism_key_map_find(&h->cells, key);
    if (i == ISM_KEY_NONE) {
        if (!h->stopped && h->worked >= RM_HCELL_TRIAL &&
            (double)h->spared < RM_HCELL_MIN_SHARE * (double)h->asked)
            h->stopped = true; /* the cells have not paid (rm_hcell.h) */
        if (h->stopped || !room(h))
            return INFINITY;
        bool added;
        if ((i = ism_key_map_add(&h->cells, key, &added)) == ISM_KEY_NONE)
            return INFINITY;
        h->m[i] = cell_bound(p, h, c, p->max_error);
        h->worked++;
    }
    h->last_key = key;
    h->last_m = h->m[i];
    return h->m[i];
}

double rm_hcell_residual(rm_pass *p, const double x[3], double s1, double gn)
{
    if (!p->hcell)
        return INFINITY;
    p->hcell->asked++;
    /* den bounds |∇f| where the step lands from below: it must clear the threshold at which
     * the second step would call ∇f vanished (rm_bound.c), or the bound would accept a point
     * the measure rejects */
    double m = bound_at(p, p->hcell, x), a = fabs(s1), den = gn - m * a;
    return den > p->gthresh ? 0.5 * m * a * a / den * (1 + 0x1p-40) : INFINITY;
}

void rm_hcell_spared(rm_pass *p)
{
    if (p->hcell)
        p->hcell->spared++;
}

void rm_hcell_counts(const rm_pass *p, size_t *asked, size_t *spared)
{
    *asked = p->hcell ? p->hcell->asked : 0;
    *spared = p->hcell ? p->hcell->spared : 0;
}
