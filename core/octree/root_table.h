/* root_table.h — the single roots the octree build's flatness test found on node edges
 * (cell_error.c: regula falsi between two corners of opposite sign), handed to the cells of
 * the same round. A leaf's cell walks its tiles' lattice segments, and a segment between two
 * consecutive break points is an edge of the smallest leaf along there, which the build
 * measured before polygonising, so its root was searched already: Barth's sextic at E 1e-2
 * searched 24,605 segment roots in the cells (88M instructions, ~3,600 each) after the build
 * had searched 31,390. The root is a pure function of the edge's two lattice points, f at
 * them and f along it (cell_cache.h ism_root_entry), so a hit is the parameter the cell's own
 * search would find, bit for bit: the mesh does not change.
 *
 * Each build thread appends what it searches to a log of its own (no lock), up to the log's
 * limit (a share of the polygoniser's memory budget: polygonise.c ROOT_MEMORY_SHARE); after
 * the build the logs go one by one into one read-only open-addressing table that every cell
 * thread asks, each freed once in it (the logs and the table do not coexist whole).
 *
 * It also owns the rule by which the build's two searchers of edge roots (cell_error.c,
 * level_prefetch.c) use a thread's direct-mapped root memo (cell_cache.h ism_root_slot):
 * ism_root_memo_find, ism_root_claim, ism_root_store, here beside the log the store appends
 * to. */
#ifndef ISM_ROOT_TABLE_H
#define ISM_ROOT_TABLE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/octree/cell_cache.h"

/* One thread's roots in the order searched (keys as ism_root_entry's: the edge's lower and
 * upper lattice key). */
typedef struct ism_root_log {
    ism_root_entry *v;
    size_t n, cap;
    size_t limit; /* roots it may hold (0: none) */
} ism_root_log;

/* Heap bytes per root the logs and the table hold at worst, for the logs' limit: a log's
 * array doubles (under 2 entries a root), and the table's power of two at SLOTS_PER_ROOT
 * (root_table.c) rounds up to under twice that (4). */
#define ISM_ROOT_BYTES (6 * sizeof(ism_root_entry))

/* Appends a root; past l->limit or out of memory it is not kept (the table is a cache: the
 * cell searches). */
void ism_root_log_push(ism_root_log *l, uint64_t a, uint64_t b, double t);
void ism_root_log_free(ism_root_log *l);

/* The thread's root memo (cell_cache.h ism_root_slot's direct-mapped slots) as the build's
 * two searchers of edge roots use it, the flatness test's (cell_error.c) and the level
 * prefetch's (level_prefetch.c): a slot answers edge a -> b when it holds both keys; a search
 * claims its slot first (a prefetch gathers many edges before it searches them, and an edge
 * met again meanwhile is not gathered twice), then stores its root where the slot still
 * holds the edge (a later claim took it over: the root is only logged) and logs it. */
static inline bool ism_root_memo_find(const ism_root_entry *slot, uint64_t a, uint64_t b,
                                      double *t)
{
    if (slot->a != a || slot->b != b)
        return false;
    *t = slot->t;
    return true;
}

static inline void ism_root_claim(ism_root_entry *slot, uint64_t a, uint64_t b)
{
    *slot = (ism_root_entry){a, b, 0};
}

static inline void ism_root_store(ism_root_entry *slot, ism_root_log *log, uint64_t a,
                                  uint64_t b, double t)
{
    if (slot->a == a && slot->b == b)
        slot->t = t;
    if (log)
        ism_root_log_push(log, a, b, t);
}

typedef struct ism_root_table {
    ism_root_entry *slots; /* linear probing; a = 0 marks an empty slot (a lattice key is
                              never 0: grid.h ism_lattice_key) */
    size_t mask;           /* slot count - 1 (a power of two); 0 with no slots */
} ism_root_table;

/* An empty table with room for `roots` roots (no slots when roots is 0 or out of memory:
 * then every find misses). */
void ism_root_table_init(ism_root_table *t, size_t roots);
/* Puts log l's roots into t (an edge already there keeps its first root), then frees l. */
void ism_root_table_take(ism_root_table *t, ism_root_log *l);
void ism_root_table_free(ism_root_table *t);

/* The root parameter from lattice key a to key b, when the build searched it. */
static inline bool ism_root_table_find(const ism_root_table *t, uint64_t a, uint64_t b,
                                       double *out)
{
    if (!t || !t->slots)
        return false;
    for (size_t s = ism_edge_slot(a, b, 63) & t->mask;; s = (s + 1) & t->mask) {
        const ism_root_entry *e = &t->slots[s];
        if (e->a == a && e->b == b) {
            *out = e->t;
            return true;
        }
        if (!e->a)
            return false;
    }
}

#endif
