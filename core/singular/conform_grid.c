/* conform_grid.c — the conformance pass's spatial index over the mesh's triangles: a loose
 * multi-level grid. A triangle is filed once, in the level whose cells are at least as large
 * as its bounding box, in the cell holding its box's centre; it then lies within half a cell
 * of that cell, so a query box grown by a cell per level finds every triangle whose box meets
 * it. Built once per pass, kept current as the surgery appends triangles and undoes them
 * (a cell's list is a stack: the last triangle filed first, popped in the reverse order).
 *
 *      level 1  ┌───────────────┬───────────────┐   a long triangle (the coarse cells
 *               │      ╱╲       │               │   far from the locus) goes up a level;
 *      level 0  ├───┬──╱─┬╲──┬───┼───┬───┬───┬───┤   a query at each level reads the cells
 *               │ ▲ │ ╱  │ ╲ │   │   │   │   │   │   its box meets, one more on each side
 *               └───┴────┴───┴───┴───┴───┴───┴───┘
 * The polygoniser's triangles are filed lazily: only those whose box meets the region the
 * surgeries have asked for (the locus grown by their radius), found by one pass over them
 * per widening of that region; most of a mesh lies far from its singular locus.
 * Cost: O(T) box tests per widening of the covered region (in blocks on the pass's threads),
 * and the filing of the triangles in it (in triangle order, on the calling thread); a query reads the cells its box meets at each level in use and the triangles filed
 * there. */
#include "core/singular/conform_internal.h"
#include "core/util/grow.h"
#include "core/util/parallel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Level-0 cell side in finest octree cells: the polygoniser's triangles at the finest depth
 * span about one cell, so most are filed at level 0 and a ball of CF_RHO_CELLS reads a few
 * dozen cells. */
#define GRID_CELLS 2.0
/* Cell coordinates per axis are packed in this many bits (clamped: a monotone clamp keeps
 * every query's answer a superset); the level-0 side grows with a box too large for it. */
#define COORD_BITS 19
#define COORD_MAX ((1 << COORD_BITS) - 1)
/* Levels of doubling cells; a triangle larger than the top one (positions far outside the
 * box) is filed in one cell read by every query. */
#define TOP_LEVEL (CF_TGRID_LEVELS - 2)

static uint64_t pack(int level, const int64_t c[3])
{
    return (uint64_t)level << (3 * COORD_BITS) | (uint64_t)c[0] << (2 * COORD_BITS) |
           (uint64_t)c[1] << COORD_BITS | (uint64_t)c[2];
}

/* Bits of the occupied filter per triangle of the mesh at cf_tgrid_init (at least
 * OCCUPIED_MIN): a grid holds at most a cell per triangle, so of the mesh at init at most a
 * quarter of the bits are set and a query's probe of an empty cell (most of those it reads:
 * the surface is thin in its box) is skipped three times in four at least. The filter is not
 * resized: triangles filed later (cf_tgrid_add from the refill and zip, split_over's halves)
 * may set more bits, which costs only speed (a set bit only lets the probe run). */
#define OCCUPIED_PER_TRI 4
#define OCCUPIED_MIN 4096 /* 2^12 */

/* The occupied filter's bit of a cell key (Fibonacci hashing: the top bits of the key times
 * 2^64 / φ, which spreads neighbouring cells' keys). */
static inline uint64_t occupied_bit(const cf_tgrid *g, uint64_t key)
{
    return (key * 0x9e3779b97f4a7c15ull) >> g->occupied_shift;
}

static inline bool maybe_occupied(const cf_tgrid *g, uint64_t key)
{
    uint64_t b = occupied_bit(g, key);
    return g->occupied[b >> 6] >> (b & 63) & 1;
}

/* floor((x − lo) / s) clamped to [0, COORD_MAX] (0 for a NaN; three per triangle filed, six
 * per level of every query). */
static int64_t coord(const cf_tgrid *g, double x, int k, double s)
{
    return cf_floor_clamped((x - g->lo[k]) / s, (int64_t)COORD_MAX + 1);
}

/* Inlined, the corners' rows taken once (a call and the indexing per coordinate cost 54
 * instructions a box: 13.7M on the Klein bottle at E 0.00327, a filing or a gather's test
 * each). */
static inline __attribute__((always_inline)) void tri_box(const ism_mesh *m, uint32_t t,
                                                          double lo[3], double hi[3])
{
    const uint32_t *v = m->tri + 3 * (size_t)t;
    const double *pa = m->pos + 3 * (size_t)v[0], *pb = m->pos + 3 * (size_t)v[1],
                 *pd = m->pos + 3 * (size_t)v[2];
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++) {
        lo[k] = cf_min2(pa[k], cf_min2(pb[k], pd[k]));
        hi[k] = cf_max2(pa[k], cf_max2(pb[k], pd[k]));
    }
}

bool cf_tgrid_init(cf_tgrid *g, const double origin[3], double extent, double finest_cell,
                   size_t ntris)
{
    memset(g, 0, sizeof *g);
    ism_key_map_init(&g->cells);
    g->last_cell = CF_NONE;
    for (int k = 0; k < 3; k++) {
        g->lo[k] = origin[k];
        g->cover[k] = INFINITY; /* empty: nothing covered yet */
        g->cover[k + 3] = -INFINITY;
    }
    g->side = fmax(GRID_CELLS * finest_cell, extent / (COORD_MAX / 2));
    if (!(g->side > 0 && isfinite(g->side)))
        return false;
    if (!cf_grow((void **)&g->next, &g->cap_next, ntris + 1, sizeof *g->next) ||
        !cf_grow((void **)&g->cell_of, &g->cap_cell_of, ntris + 1, sizeof *g->cell_of) ||
        !cf_grow((void **)&g->stamp, &g->cap_stamp, ntris + 1, sizeof *g->stamp))
        return false;
    memset(g->cell_of, 0xff, ntris * sizeof *g->cell_of); /* CF_NONE: not filed */
    size_t bits = OCCUPIED_MIN;
    g->occupied_shift = 64 - 12; /* log2(OCCUPIED_MIN) */
    for (; bits < OCCUPIED_PER_TRI * ntris && bits < ((size_t)1 << 40); bits *= 2)
        g->occupied_shift--;
    if (!(g->occupied = calloc(bits / 64, sizeof *g->occupied)))
        return false;
    g->ntris = g->base = ntris;
    return true;
}

void cf_tgrid_free(cf_tgrid *g)
{
    ism_key_map_free(&g->cells);
    free(g->head);
    free(g->next);
    free(g->cell_of);
    free(g->stamp);
    free(g->cell_box);
    free(g->occupied);
    memset(g, 0, sizeof *g);
}

/* Files triangle t: pushed on its cell's stack, or, for one of the first `base` filed late,
 * below the appended triangles there (cf_tgrid_truncate pops those from the top). */
static bool file_triangle(cf_tgrid *g, const ism_mesh *m, uint32_t t)
{
    /* room not zeroed (ism_grow): a triangle's next, cell_of and stamp are written here, as
     * it is filed, before anything reads them (cf_grow's zeroing of the doublings cost the
     * Klein bottle at E 0.00327 5.3M instructions) */
    size_t need = (size_t)t + 1;
    if ((need > g->cap_next || need > g->cap_cell_of || need > g->cap_stamp) &&
        (!ism_grow((void **)&g->next, &g->cap_next, need, sizeof *g->next, need) ||
         !ism_grow((void **)&g->cell_of, &g->cap_cell_of, need, sizeof *g->cell_of, need) ||
         !ism_grow((void **)&g->stamp, &g->cap_stamp, need, sizeof *g->stamp, need)))
        return false;
    double lo[3], hi[3], s = g->side;
    tri_box(m, t, lo, hi);
    double e = cf_max2(hi[0] - lo[0], cf_max2(hi[1] - lo[1], hi[2] - lo[2]));
    int level = 0;
    while (level < TOP_LEVEL && !(e <= s)) {
        s *= 2;
        level++;
    }
    int64_t c[3] = {0, 0, 0};
    if (e <= s)
        for (int k = 0; k < 3; k++)
            c[k] = coord(g, 0.5 * (lo[k] + hi[k]), k, s);
    else
        level = TOP_LEVEL + 1; /* too large for any level (or not finite): read always */
    bool added = false;
    uint64_t key = pack(level, c);
    uint32_t cell = key == g->last_key && g->last_cell != CF_NONE
                        ? g->last_cell
                        : ism_key_map_add(&g->cells, key, &added);
    g->last_key = key;
    g->last_cell = cell;
    if (cell == ISM_KEY_NONE)
        return false;
    size_t cells = (size_t)cell + 1;
    if ((cells > g->cap_head || 6 * cells > g->cap_cell_box) &&
        (!cf_grow((void **)&g->head, &g->cap_head, cells, sizeof *g->head) ||
         !cf_grow((void **)&g->cell_box, &g->cap_cell_box, 6 * cells, sizeof *g->cell_box)))
        return false;
    double *cb = g->cell_box + 6 * (size_t)cell;
    if (added) {
        uint64_t b = occupied_bit(g, key);
        g->occupied[b >> 6] |= (uint64_t)1 << (b & 63);
        g->head[cell] = CF_NONE;
        for (int k = 0; k < 3; k++) {
            cb[k] = lo[k];
            cb[k + 3] = hi[k];
        }
    }
    for (int k = 0; k < 3; k++) { /* the union of the boxes ever filed there */
        cb[k] = cf_min2(cb[k], lo[k]);
        cb[k + 3] = cf_max2(cb[k + 3], hi[k]);
    }
    uint32_t *link = &g->head[cell];
    if (t < g->base)
        while (*link != CF_NONE && *link >= g->base)
            link = &g->next[*link];
    g->next[t] = *link;
    *link = t;
    g->cell_of[t] = cell;
    g->stamp[t] = 0;
    g->per_level[level]++;
    return true;
}

bool cf_tgrid_add(cf_tgrid *g, const ism_mesh *m, uint32_t t)
{
    if (!file_triangle(g, m, t))
        return false;
    g->ntris = (size_t)t + 1;
    return true;
}

static bool box_inside(const double lo[3], const double hi[3], const double box[6])
{
    for (int k = 0; k < 3; k++)
        if (!(lo[k] >= box[k] && hi[k] <= box[k + 3]))
            return false;
    return true;
}

/* How far a widening reaches, and from which pass on: CF_COVER_GROWTH, CF_COVER_PLAIN_PASSES
 * (conform_internal.h, where the grid's tests read them). */

/* Vertices or triangles per task of a cover pass: fixed, so the triangles it files, and
 * their order, are the same on any number of threads. */
#define COVER_BLOCK 16384

/* One pass over the first `base` triangles: the ones not filed yet whose boxes meet want,
 * per block in triangle order (found on the grid's threads, filed after on the caller's). */
typedef struct cover_pass {
    const cf_tgrid *g;
    const ism_mesh *m;
    double want[6];
    uint8_t *out;   /* per vertex: which of want's six planes it lies beyond (a bit each) */
    cf_tris *found; /* per block of triangles */
    int failed;
} cover_pass;

static void outcode_block(void *ctx, size_t blk, int thread)
{
    (void)thread;
    const cover_pass *c = ctx;
    /* want and the bounds in locals: the byte stores to out may alias anything, so read
       through c each vertex re-loaded them (68 instructions a vertex before) */
    double w[6];
    memcpy(w, c->want, sizeof w);
    const double *pos = c->m->pos;
    uint8_t *out = c->out;
    size_t end = ism_block_end(blk, COVER_BLOCK, c->m->nverts);
    for (size_t v = blk * COVER_BLOCK; v < end; v++) {
        const double *p = pos + 3 * v;
        unsigned o = 0;
        _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
            o |= (unsigned)(p[k] < w[k]) << (2 * k) | (unsigned)(p[k] > w[k + 3]) << (2 * k + 1);
        out[v] = (uint8_t)o;
    }
}

/* a triangle's box misses the box exactly when its three corners lie beyond one of the
 * box's six planes: the AND of their outcodes */
static void cover_block(void *ctx, size_t blk, int thread)
{
    (void)thread;
    cover_pass *c = ctx;
    const uint8_t *out = c->out;
    const uint32_t *tri = c->m->tri, *cell_of = c->g->cell_of;
    size_t end = ism_block_end(blk, COVER_BLOCK, c->g->base);
    for (size_t t = blk * COVER_BLOCK; t < end; t++) {
        const uint32_t *v = tri + 3 * t;
        if (!(out[v[0]] & out[v[1]] & out[v[2]]) && cell_of[t] == CF_NONE &&
            !cf_tris_push(&c->found[blk], (uint32_t)t))
            __atomic_store_n(&c->failed, 1, __ATOMIC_RELAXED);
    }
}

bool cf_tgrid_cover(cf_tgrid *g, const ism_mesh *m, const double lo[3], const double hi[3],
                    double ahead)
{
    if (box_inside(lo, hi, g->cover))
        return true;
    cover_pass c = {.g = g, .m = m};
    double grown = 0; /* the covered box's largest side (0 while empty) */
    for (int k = 0; k < 3; k++)
        grown = fmax(grown, g->cover[k + 3] - g->cover[k]);
    if (g->cover_passes >= CF_COVER_PLAIN_PASSES)
        ahead = fmax(ahead, CF_COVER_GROWTH * grown);
    for (int k = 0; k < 3; k++) {
        c.want[k] = fmin(g->cover[k], lo[k] - ahead);
        c.want[k + 3] = fmax(g->cover[k + 3], hi[k] + ahead);
    }
    g->cover_passes++;
    size_t vblocks = ism_blocks(m->nverts, COVER_BLOCK);
    size_t tblocks = ism_blocks(g->base, COVER_BLOCK);
    c.out = malloc(m->nverts + 1);
    c.found = calloc(tblocks ? tblocks : 1, sizeof *c.found);
    bool ok = c.out && c.found;
    if (ok) {
        ism_parallel_for(vblocks > 1 ? g->threads : 1, vblocks, outcode_block, &c);
        ism_parallel_for(tblocks > 1 ? g->threads : 1, tblocks, cover_block, &c);
        ok = !c.failed;
    }
    for (size_t b = 0; c.found && b < tblocks; b++) {
        for (size_t i = 0; ok && i < c.found[b].n; i++)
            ok = file_triangle(g, m, c.found[b].t[i]);
        free(c.found[b].t);
    }
    free(c.found);
    free(c.out);
    if (ok)
        memcpy(g->cover, c.want, sizeof c.want);
    return ok;
}

void cf_tgrid_truncate(cf_tgrid *g, size_t ntris)
{
    while (g->ntris > ntris) {
        uint32_t t = (uint32_t)--g->ntris, cell = g->cell_of[t];
        if (cell == CF_NONE)
            continue; /* one of the first base, never filed */
        g->head[cell] = g->next[t];
        g->per_level[g->cells.keys[cell] >> (3 * COORD_BITS)]--;
    }
}

void cf_tgrid_begin(cf_tgrid *g)
{
    if (++g->epoch == 0) { /* wrapped: forget every stamp */
        memset(g->stamp, 0, g->ntris * sizeof *g->stamp);
        g->epoch = 1;
    }
}

/* Triangles a list first has room for (as cf_grow's first allocation). */
#define TRIS_FIRST 64

bool cf_tris_push(cf_tris *out, uint32_t t)
{
    /* not zeroed (ism_grow): the list is read only up to n */
    if (out->n == out->cap &&
        !ism_grow((void **)&out->t, &out->cap, out->n + 1, sizeof *out->t, TRIS_FIRST))
        return false;
    out->t[out->n++] = t;
    return true;
}

/* A query: its box, the mesh and the dead marks. */
typedef struct query {
    const ism_mesh *m;
    const uint8_t *dead;
    double lo[3], hi[3];
} query;

/* The triangles of one cell whose boxes meet the query's, not yet gathered since
 * cf_tgrid_begin and not dead. */
static bool take_cell(cf_tgrid *g, uint32_t cell, const query *q, cf_tris *out)
{
    const double *cb = g->cell_box + 6 * (size_t)cell;
    for (int k = 0; k < 3; k++)
        if (!(cb[k] <= q->hi[k] && cb[k + 3] >= q->lo[k]))
            return true; /* no triangle of the cell reaches the query's box */
    for (uint32_t t = g->head[cell]; t != CF_NONE; t = g->next[t]) {
        if (g->stamp[t] == g->epoch || q->dead[t])
            continue;
        double lo[3], hi[3];
        tri_box(q->m, t, lo, hi);
        if (!(lo[0] <= q->hi[0] && hi[0] >= q->lo[0] && lo[1] <= q->hi[1] &&
              hi[1] >= q->lo[1] && lo[2] <= q->hi[2] && hi[2] >= q->lo[2]))
            continue;
        g->stamp[t] = g->epoch;
        if (!cf_tris_push(out, t))
            return false;
    }
    return true;
}

static bool gather_level(cf_tgrid *g, int level, const query *q, cf_tris *out)
{
    double s = ldexp(g->side, level);
    int64_t a[3], b[3], c[3];
    size_t span = 1;
    for (int k = 0; k < 3; k++) {
        /* a triangle's box lies within half a cell of its cell: one more cell each side */
        a[k] = coord(g, q->lo[k], k, s) - 1;
        b[k] = coord(g, q->hi[k], k, s) + 1;
        a[k] = a[k] < 0 ? 0 : a[k];
        b[k] = b[k] > COORD_MAX ? COORD_MAX : b[k];
        span *= (size_t)(b[k] - a[k] + 1);
    }
    if (span > g->cells.n) { /* a box larger than the occupied cells: read those instead */
        for (uint32_t cell = 0; cell < g->cells.n; cell++) {
            uint64_t key = g->cells.keys[cell];
            bool in = (int)(key >> (3 * COORD_BITS)) == level;
            for (int k = 0; k < 3 && in; k++) {
                int64_t x = (int64_t)(key >> ((2 - k) * COORD_BITS)) & COORD_MAX;
                in = x >= a[k] && x <= b[k];
            }
            if (in && !take_cell(g, cell, q, out))
                return false;
        }
        return true;
    }
    for (c[0] = a[0]; c[0] <= b[0]; c[0]++)
        for (c[1] = a[1]; c[1] <= b[1]; c[1]++)
            for (c[2] = a[2]; c[2] <= b[2]; c[2]++) {
                uint64_t key = pack(level, c);
                if (!maybe_occupied(g, key))
                    continue; /* never added: the map would answer none */
                uint32_t cell = ism_key_map_find(&g->cells, key);
                if (cell != ISM_KEY_NONE && !take_cell(g, cell, q, out))
                    return false;
            }
    return true;
}

bool cf_tgrid_gather(cf_tgrid *g, const ism_mesh *m, const double lo[3], const double hi[3],
                     const uint8_t *dead, cf_tris *out)
{
    if (!cf_tgrid_cover(g, m, lo, hi, 0))
        return false;
    query q = {m, dead, {lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
    for (int level = 0; level <= TOP_LEVEL; level++)
        if (g->per_level[level] && !gather_level(g, level, &q, out))
            return false;
    if (g->per_level[TOP_LEVEL + 1]) {
        uint32_t cell = ism_key_map_find(&g->cells, pack(TOP_LEVEL + 1, (const int64_t[3]){0}));
        if (cell != ISM_KEY_NONE && !take_cell(g, cell, &q, out))
            return false;
    }
    return true;
}

void cf_query_box(const double a[3], const double b[3], double r, double lo[3], double hi[3])
{
    double mag = 0;
    for (int k = 0; k < 3; k++)
        mag = fmax(mag, fmax(fabs(a[k]), fabs(b[k])));
    double grow_by = r + CF_QUERY_SLACK * (r + mag);
    for (int k = 0; k < 3; k++) {
        lo[k] = fmin(a[k], b[k]) - grow_by;
        hi[k] = fmax(a[k], b[k]) + grow_by;
    }
}
