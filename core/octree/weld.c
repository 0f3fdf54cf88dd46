/* weld.c — exact-position welding of node outputs, in parallel over the pieces, and the
 * vertex normals: ∇f normalised, or the mean of the adjacent triangles' normals where the
 * gradient vanishes (singular points).
 *
 * Every piece vertex has a number (its piece, then its place in the piece); a lock-free
 * open-addressing table keeps, per distinct position, the smallest number that has it (a
 * compare-and-swap minimum), whatever order the threads insert in. The vertices holding that
 * smallest number become the mesh's vertices, numbered in piece order; the others take
 * their index. Six loops over the pieces, each one piece per task, with prefix sums over
 * the pieces between them: dedupe within the piece (most duplicates are neighbours in one
 * chunk: a small table in the thread's cache); insert the piece's first occurrences in the
 * shared table; resolve (count new vertices); place (write them); map (count kept
 * triangles); write the triangles. */
#include "core/octree/weld.h"
#include "core/util/pool.h"
#include "core/util/vec3.h"
#include "core/util/zeroed.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

/* Table slots per piece vertex, at least: probes stay short at a load of 1/2 or less. */
#define SLOTS_PER_VERTEX 2
/* Vertex numbers, and the slot numbers of a table of up to 4 slots per vertex (2 rounded up
 * to a power of two), fit in 32 bits below this. */
#define MAX_PIECE_VERTICES ((size_t)1 << 30)

/* The larger of a and b by comparison (b when either is NaN), not libm's fmax: a call per
 * vertex's component. */
static double larger(double a, double b) { return a > b ? a : b; }

/* g scaled to unit length, or 0 0 0 when g is zero or not finite. Dividing by the largest
 * component first keeps the squared length from underflowing (∇f ~ 1e-160 where f = g^64
 * nears its zero gave normals of length 1.015) or overflowing. A NaN component gives 0 0 0
 * whatever big then is (NaN: no scaling; a number: a NaN length), as with fmax. */
static void unit_normal(const double g[3], float n[3])
{
    double big = larger(fabs(g[0]), larger(fabs(g[1]), fabs(g[2]))), s[3] = {0, 0, 0}, len = 0;
    if (big > 0 && isfinite(big)) {
        for (int k = 0; k < 3; k++)
            s[k] = g[k] / big;
        len = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    }
    for (int k = 0; k < 3; k++)
        n[k] = len > 0 ? (float)(s[k] / len) : 0.0f; /* NaN len: no normal */
}

/* A position's hash: one multiply per coordinate's bits, their high halves folded into the
 * low (the slot: h & mask; the tag: h's high half). The tables only map positions to
 * numbers, so the hash decides no vertex, only how far a probe runs. */
static uint64_t hash_point(const double p[3])
{
    uint64_t b[3];
    for (int k = 0; k < 3; k++) {
        /* -0.0 and 0.0 are one point (same_point): −0 + 0 = +0, else v = p[k]. IEEE keeps
           this add; -ffast-math or -fno-signed-zeros would drop it, and a −0 copy would then
           hash away from its +0 twin and never be joined (test_weld_negative_zero). */
        double v = p[k] + 0.0;
        memcpy(&b[k], &v, sizeof b[k]);
    }
    uint64_t h = b[0] * 0x9e3779b97f4a7c15ull ^ b[1] * 0xc2b2ae3d27d4eb4full ^
                 b[2] * 0x165667b19e3779f9ull;
    return h ^ (h >> 32);
}

static bool same_point(const double a[3], const double b[3])
{
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

typedef struct welder {
    const ism_cell_out *pieces;
    _Atomic uint64_t *slots; /* hash tag << 32 | (number + 1) of a position's first
                                occurrence; 0: empty */
    size_t mask;
    size_t *voff;            /* per piece: the number of its first vertex (npieces + 1) */
    const double **at;       /* per vertex number: its position (first in its piece only) */
    uint64_t *hash;          /* per vertex number: hash_point of it (same) */
    uint32_t *slot;          /* per vertex number: its position's slot (same) */
    uint32_t *rep;           /* per vertex number: the number of its position's first in
                                its piece, then its first in all */
    uint32_t *local;         /* per thread: a table of local_cap slots for one piece */
    size_t local_cap;
    size_t *distinct;        /* per piece: positions first in it */
    uint32_t *index;         /* per vertex number: its index in the mesh */
    size_t *new_verts, *kept_tris; /* per piece; then, after the prefix sums, where its new
                                      vertices / kept triangles start in the mesh */
    ism_weld_stats *piece_st;
    ism_mesh *mesh;
} welder;

#define NUMBER_OF(slot) ((uint32_t)(slot) - 1)

/* Records vertex number g at p (its hash h), keeping the smallest number per position, and
 * notes its slot. The tag (the hash's high half) spares reading the positions of most other
 * keys. */
static void insert(welder *w, uint32_t g, const double p[3], uint64_t h)
{
    uint64_t tag = h & 0xffffffff00000000ull, mine = tag | (g + 1ull);
    for (size_t i = h & w->mask;; i = (i + 1) & w->mask) {
        uint64_t cur = atomic_load_explicit(&w->slots[i], memory_order_relaxed);
        while (!cur) /* an empty slot: take it, or see who did */
            if (atomic_compare_exchange_weak(&w->slots[i], &cur, mine)) {
                w->slot[g] = (uint32_t)i;
                return;
            }
        if ((cur & 0xffffffff00000000ull) != tag || !same_point(w->at[NUMBER_OF(cur)], p))
            continue;
        while (mine < cur && !atomic_compare_exchange_weak(&w->slots[i], &cur, mine))
            ;
        w->slot[g] = (uint32_t)i;
        return;
    }
}

/* The slot of p (its hash h) in a piece's own table (piece-local vertex index + 1; 0:
 * empty). */
static uint32_t *local_slot(uint32_t *table, size_t mask, const ism_fpoint *v, const double p[3],
                            uint64_t h)
{
    for (size_t i = h & mask;; i = (i + 1) & mask)
        if (!table[i] || same_point(v[table[i] - 1].p, p))
            return &table[i];
}

/* Pass 1: each vertex's first occurrence within its piece (a table in the thread's cache:
 * most duplicates are neighbouring nodes of one chunk). */
static void dedupe_piece(void *ctx, size_t k, int thread)
{
    welder *w = ctx;
    const ism_cell_out *o = &w->pieces[k];
    uint32_t *table = w->local + (size_t)thread * w->local_cap;
    size_t cap = 16, first = w->voff[k], distinct = 0;
    while (cap < SLOTS_PER_VERTEX * o->nverts)
        cap *= 2;
    memset(table, 0, cap * sizeof *table);
    for (size_t i = 0; i < o->nverts; i++) {
        uint64_t h = hash_point(o->verts[i].p);
        uint32_t *e = local_slot(table, cap - 1, o->verts, o->verts[i].p, h);
        if (!*e) {
            *e = (uint32_t)i + 1;
            w->at[first + i] = o->verts[i].p;
            w->hash[first + i] = h; /* for the shared table (insert_piece) */
            distinct++;
        }
        w->rep[first + i] = (uint32_t)(first + *e - 1);
    }
    w->distinct[k] = distinct;
}

/* Pass 2: the piece's first occurrences into the shared table. */
static void insert_piece(void *ctx, size_t k, int thread)
{
    (void)thread;
    welder *w = ctx;
    for (size_t g = w->voff[k]; g < w->voff[k + 1]; g++)
        if (w->rep[g] == g)
            insert(w, (uint32_t)g, w->at[g], w->hash[g]);
}

/* Pass 3: every vertex's first occurrence in all pieces; counts the piece's new vertices. */
static void resolve_piece(void *ctx, size_t k, int thread)
{
    (void)thread;
    welder *w = ctx;
    size_t fresh = 0;
    for (size_t g = w->voff[k]; g < w->voff[k + 1]; g++) {
        if (w->rep[g] == g) /* first in the piece: the shared table knows */
            w->rep[g] = NUMBER_OF(atomic_load_explicit(&w->slots[w->slot[g]],
                                                       memory_order_relaxed));
        else /* a later one: its piece's first, resolved just before */
            w->rep[g] = w->rep[w->rep[g]];
        fresh += w->rep[g] == g;
    }
    w->new_verts[k] = fresh;
}

static void count_kind(ism_weld_stats *st, uint8_t flags)
{
    st->zero_vertices += (flags & ISM_FP_ZERO) != 0;
    st->touch_vertices += (flags & ISM_FP_TOUCH) != 0;
    st->pair_vertices += (flags & ISM_FP_PAIR) != 0;
    st->many_vertices += (flags & ISM_FP_MANY) != 0;
}

static void place_piece(void *ctx, size_t k, int thread)
{
    (void)thread;
    welder *w = ctx;
    const ism_cell_out *o = &w->pieces[k];
    size_t at = w->new_verts[k];
    for (size_t i = 0; i < o->nverts; i++) {
        size_t g = w->voff[k] + i;
        if (w->rep[g] != g)
            continue;
        w->index[g] = (uint32_t)at;
        memcpy(w->mesh->pos + 3 * at, o->verts[i].p, sizeof o->verts[i].p);
        unit_normal(o->verts[i].g, w->mesh->normal + 3 * at);
        count_kind(&w->piece_st[k], o->verts[i].flags);
        at++;
    }
}

static bool degenerate(const uint32_t *map, const uint32_t *tri)
{
    uint32_t a = map[tri[0]], b = map[tri[1]], c = map[tri[2]];
    return a == b || b == c || a == c;
}

static void map_piece(void *ctx, size_t k, int thread)
{
    (void)thread;
    welder *w = ctx;
    const ism_cell_out *o = &w->pieces[k];
    uint32_t *map = w->index + w->voff[k];
    for (size_t i = 0; i < o->nverts; i++) { /* first occurrences were placed already */
        size_t g = w->voff[k] + i;
        if (w->rep[g] != g)
            map[i] = w->index[w->rep[g]];
    }
    size_t kept = 0;
    for (size_t i = 0; i < o->ntris; i++)
        kept += !degenerate(map, o->tris + 3 * i);
    w->kept_tris[k] = kept;
    w->piece_st[k].dropped_triangles = o->ntris - kept;
}

static void write_piece(void *ctx, size_t k, int thread)
{
    (void)thread;
    welder *w = ctx;
    const ism_cell_out *o = &w->pieces[k];
    const uint32_t *map = w->index + w->voff[k];
    uint32_t *out = w->mesh->tri + 3 * w->kept_tris[k];
    for (size_t i = 0; i < o->ntris; i++) {
        const uint32_t *t = o->tris + 3 * i;
        if (degenerate(map, t))
            continue;
        for (int j = 0; j < 3; j++)
            *out++ = map[t[j]];
    }
}

/* Vertices or triangles per task of the normal fill-in below: fixed, so its sums run in the
 * same order on any number of threads. */
#define FILL_BLOCK 8192

/* The vertices whose ∇f vanished (singular points) and the triangles around them. */
typedef struct filler {
    ism_mesh *m;
    uint32_t *number; /* per vertex: 1 + its place among the vertices without a normal; 0 */
    size_t *per_block; /* such vertices per block, then where the block's start; then the
                          triangles touching them per block */
    uint32_t *touching; /* per block of triangles, from its first triangle's place on: those
                           with such a corner, in triangle order */
    double *acc;        /* per such vertex: the sum of its triangles' normals */
} filler;

static size_t fill_end(size_t blk, size_t n)
{
    return (blk + 1) * FILL_BLOCK < n ? (blk + 1) * FILL_BLOCK : n;
}

static bool no_normal(const float *n) { return n[0] == 0 && n[1] == 0 && n[2] == 0; }

static void count_missing(void *ctx, size_t blk, int thread)
{
    (void)thread;
    filler *f = ctx;
    size_t n = 0;
    for (size_t v = blk * FILL_BLOCK; v < fill_end(blk, f->m->nverts); v++)
        n += no_normal(f->m->normal + 3 * v);
    f->per_block[blk] = n;
}

static void number_missing(void *ctx, size_t blk, int thread)
{
    (void)thread;
    filler *f = ctx;
    uint32_t next = (uint32_t)f->per_block[blk];
    for (size_t v = blk * FILL_BLOCK; v < fill_end(blk, f->m->nverts); v++)
        f->number[v] = no_normal(f->m->normal + 3 * v) ? ++next : 0;
}

static bool touches(const filler *f, size_t t)
{
    const uint32_t *c = f->m->tri + 3 * t;
    return f->number[c[0]] || f->number[c[1]] || f->number[c[2]];
}

static void list_touching(void *ctx, size_t blk, int thread)
{
    (void)thread;
    filler *f = ctx;
    uint32_t *out = f->touching + blk * FILL_BLOCK;
    size_t n = 0;
    for (size_t t = blk * FILL_BLOCK; t < fill_end(blk, f->m->ntris); t++)
        if (touches(f, t))
            out[n++] = (uint32_t)t;
    f->per_block[blk] = n;
}

static void set_missing(void *ctx, size_t blk, int thread)
{
    (void)thread;
    filler *f = ctx;
    for (size_t v = blk * FILL_BLOCK; v < fill_end(blk, f->m->nverts); v++)
        if (f->number[v])
            unit_normal(f->acc + 3 * (f->number[v] - 1), f->m->normal + 3 * v);
}

/* Triangle t's normal (twice its area long) added to its corners that have no normal. */
static void add_normal(filler *f, uint32_t t)
{
    const ism_mesh *m = f->m;
    const uint32_t *tri = m->tri + 3 * (size_t)t;
    double n[3];
    ism_tri_cross3(m->pos + 3 * tri[0], m->pos + 3 * tri[1], m->pos + 3 * tri[2], n);
    for (int k = 0; k < 3; k++)
        if (f->number[tri[k]])
            for (int j = 0; j < 3; j++)
                f->acc[3 * (f->number[tri[k]] - 1) + j] += n[j];
}

/* Normals where ∇f vanished: the mean of the adjacent triangles' normals, added up in
 * triangle order on the calling thread; finding those vertices and triangles runs in
 * blocks on pool (each block of triangles lists its own in place: one pass). */
static void fill_missing_normals(ism_mesh *m, ism_pool *pool, ism_par_cost *cost)
{
    size_t vblocks = (m->nverts + FILL_BLOCK - 1) / FILL_BLOCK;
    size_t tblocks = (m->ntris + FILL_BLOCK - 1) / FILL_BLOCK;
    size_t most = vblocks > tblocks ? vblocks : tblocks;
    filler f = {m, NULL, malloc((most ? most : 1) * sizeof(size_t)), NULL, NULL};
    if (!f.per_block)
        return;
    ism_pool_for(pool, vblocks, count_missing, &f, cost);
    size_t missing = ism_counts_to_offsets(f.per_block, vblocks);
    if (missing && (f.number = malloc(m->nverts * sizeof *f.number)) &&
        (f.acc = calloc(3 * missing, sizeof *f.acc))) {
        ism_pool_for(pool, vblocks, number_missing, &f, cost);
        if ((f.touching = malloc((m->ntris ? m->ntris : 1) * sizeof *f.touching))) {
            ism_pool_for(pool, tblocks, list_touching, &f, cost);
            for (size_t blk = 0; blk < tblocks; blk++) /* triangle order */
                for (size_t i = 0; i < f.per_block[blk]; i++)
                    add_normal(&f, f.touching[blk * FILL_BLOCK + i]);
            ism_pool_for(pool, vblocks, set_missing, &f, cost);
        }
    }
    free(f.per_block);
    free(f.number);
    free(f.touching);
    free(f.acc);
}

/* The one-edge polygons, in piece order (few: no loop of their own). */
static bool add_segments(const welder *w, size_t npieces)
{
    for (size_t k = 0; k < npieces; k++) {
        const ism_cell_out *o = &w->pieces[k];
        const uint32_t *map = w->index + w->voff[k];
        for (size_t i = 0; i < o->nsegs; i++) {
            uint32_t a = map[o->segs[2 * i]], b = map[o->segs[2 * i + 1]];
            if (a != b && !ism_mesh_add_segment(w->mesh, a, b))
                return false;
        }
    }
    return true;
}

/* The shared table, sized by the positions first in their pieces. */
static bool alloc_table(welder *w, size_t npieces, ism_pool *pool, ism_par_cost *cost)
{
    size_t distinct = 0, cap = 16;
    for (size_t k = 0; k < npieces; k++)
        distinct += w->distinct[k];
    while (cap < SLOTS_PER_VERTEX * distinct)
        cap *= 2;
    w->mask = cap - 1;
    /* all-zero bytes: every slot empty (zeroed by writing: inserts read a slot first) */
    w->slots = ism_zeroed_alloc(pool, cap, sizeof *w->slots, cost);
    return w->slots != NULL;
}

static bool weld_all(welder *w, size_t npieces, ism_pool *pool, ism_par_cost *cost)
{
    ism_mesh *m = w->mesh;
    ism_pool_for(pool, npieces, dedupe_piece, w, cost);
    if (!alloc_table(w, npieces, pool, cost))
        return false;
    ism_pool_for(pool, npieces, insert_piece, w, cost);
    ism_pool_for(pool, npieces, resolve_piece, w, cost);
    size_t nverts = ism_counts_to_offsets(w->new_verts, npieces);
    if (!ism_mesh_reserve(m, nverts, 0))
        return false;
    m->nverts = nverts;
    ism_pool_for(pool, npieces, place_piece, w, cost);
    ism_pool_for(pool, npieces, map_piece, w, cost);
    size_t ntris = ism_counts_to_offsets(w->kept_tris, npieces);
    if (!ism_mesh_reserve(m, 0, ntris))
        return false;
    m->ntris = ntris;
    ism_pool_for(pool, npieces, write_piece, w, cost);
    return add_segments(w, npieces);
}

bool ism_weld(const ism_cell_out *pieces, size_t npieces, ism_pool *pool, ism_mesh *mesh,
              ism_weld_stats *st, ism_par_cost *cost)
{
    memset(st, 0, sizeof *st);
    welder w;
    memset(&w, 0, sizeof w);
    w.pieces = pieces;
    w.mesh = mesh;
    int threads = ism_pool_threads(pool);
    threads = threads > ISM_MAX_THREADS ? ISM_MAX_THREADS : threads;
    size_t n = npieces ? npieces : 1;
    w.voff = malloc((n + 1) * sizeof *w.voff);
    w.new_verts = malloc(n * sizeof *w.new_verts);
    w.kept_tris = malloc(n * sizeof *w.kept_tris);
    w.distinct = malloc(n * sizeof *w.distinct);
    w.piece_st = calloc(n, sizeof *w.piece_st);
    bool ok = w.voff && w.new_verts && w.kept_tris && w.distinct && w.piece_st;
    size_t total = 0, largest = 0;
    for (size_t k = 0; ok && k < npieces; k++) {
        w.voff[k] = total;
        total += pieces[k].nverts;
        largest = pieces[k].nverts > largest ? pieces[k].nverts : largest;
    }
    ok = ok && total < MAX_PIECE_VERTICES;
    if (ok) {
        w.voff[npieces] = total;
        w.local_cap = 16;
        while (w.local_cap < SLOTS_PER_VERTEX * largest)
            w.local_cap *= 2;
        w.local = malloc((size_t)threads * w.local_cap * sizeof *w.local);
        size_t room = total ? total : 1;
        w.at = malloc(room * sizeof *w.at);
        w.hash = malloc(room * sizeof *w.hash);
        w.slot = malloc(room * sizeof *w.slot);
        w.rep = malloc(room * sizeof *w.rep);
        w.index = malloc(room * sizeof *w.index);
        ok = w.local && w.at && w.hash && w.slot && w.rep && w.index &&
             weld_all(&w, npieces, pool, cost);
    }
    for (size_t k = 0; ok && k < npieces; k++) {
        const ism_weld_stats *p = &w.piece_st[k];
        st->zero_vertices += p->zero_vertices;
        st->touch_vertices += p->touch_vertices;
        st->pair_vertices += p->pair_vertices;
        st->many_vertices += p->many_vertices;
        st->dropped_triangles += p->dropped_triangles;
    }
    free(w.slots);
    free(w.local);
    free(w.distinct);
    free(w.at);
    free(w.hash);
    free(w.slot);
    free(w.rep);
    free(w.index);
    free(w.voff);
    free(w.new_verts);
    free(w.kept_tris);
    free(w.piece_st);
    if (ok)
        fill_missing_normals(mesh, pool, cost);
    return ok;
}
