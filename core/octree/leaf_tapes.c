/* leaf_tapes.c — the table of the leaves' shortened tapes (leaf_tapes.h). */
#include "core/octree/leaf_tapes.h"
#include "core/util/grow.h"

#include <stdlib.h>
#include <string.h>

/* Slots of the shared index when the first tape arrives (doubled as it fills). */
#define INDEX_FIRST 64

static size_t tape_bytes(const ism_tape *t)
{
    return sizeof *t + t->len * sizeof *t->code;
}

static ism_tape *copy_of(const ism_tape *t)
{
    ism_tape *c = ism_tape_alloc(t->len ? t->len : 1, t->nregs);
    if (!c)
        return NULL;
    memcpy(c->code, t->code, t->len * sizeof *t->code);
    c->len = t->len;
    c->result = t->result;
    c->origin_len = t->origin_len;
    return c;
}

static uint64_t mix(uint64_t h, uint64_t x)
{
    h ^= x;
    h *= 0x9e3779b97f4a7c15ull;
    return h ^ (h >> 29);
}

/* Field by field, as ism_leaf_tapes_same compares: an instruction's padding bytes are not
 * part of it. */
static uint64_t hash_of(const ism_tape *t)
{
    uint64_t h = mix(mix(mix(0x243f6a8885a308d3ull, t->len), t->result), t->nregs);
    for (size_t i = 0; i < t->len; i++) {
        const ism_instr *x = &t->code[i];
        uint64_t imm;
        memcpy(&imm, &x->imm, sizeof imm);
        h = mix(h, (uint64_t)x->op | (uint64_t)x->out << 8 | (uint64_t)x->a << 40);
        h = mix(mix(h, x->b), imm);
    }
    return h;
}

bool ism_leaf_tapes_same(const ism_tape *a, const ism_tape *b)
{
    if (a->len != b->len || a->result != b->result || a->nregs != b->nregs)
        return false;
    for (size_t i = 0; i < a->len; i++) {
        const ism_instr *x = &a->code[i], *y = &b->code[i];
        if (x->op != y->op || x->out != y->out || x->a != y->a || x->b != y->b ||
            memcmp(&x->imm, &y->imm, sizeof x->imm) != 0)
            return false;
    }
    return true;
}

/* The index slot of the tape equal to t (hash h), or the free slot where it would go (lock
 * held). */
static ism_leaf_tape_slot *slot_of(const ism_leaf_tapes *lt, uint64_t h, const ism_tape *t)
{
    size_t mask = lt->index_cap - 1;
    uint32_t tag = (uint32_t)(h >> 32);
    for (size_t i = (size_t)h & mask;; i = (i + 1) & mask) {
        ism_leaf_tape_slot *s = &lt->index[i];
        if (s->number == 0 || (s->tag == tag && ism_leaf_tapes_same(lt->v[s->number - 1], t)))
            return s;
    }
}

static void put(ism_leaf_tapes *lt, uint64_t h, unsigned number)
{
    *slot_of(lt, h, lt->v[number - 1]) = (ism_leaf_tape_slot){number, (uint32_t)(h >> 32)};
}

/* Room in the index for one more tape at half load at most (lock held): a larger index
 * rehashes the tapes (each doubling costs as much as hashing them once). */
static bool index_room(ism_leaf_tapes *lt)
{
    if (2 * (lt->n + 1) <= lt->index_cap)
        return true;
    size_t cap = lt->index_cap ? 2 * lt->index_cap : INDEX_FIRST;
    ism_leaf_tape_slot *idx = calloc(cap, sizeof *idx);
    if (!idx)
        return false;
    free(lt->index);
    lt->index = idx;
    lt->index_cap = cap;
    for (size_t k = 0; k < lt->n; k++)
        put(lt, hash_of(lt->v[k]), (unsigned)k + 1);
    return true;
}

/* Adds a copy of t (hash h) as the next number; 0 at a limit or out of memory (lock held). */
static unsigned add(ism_leaf_tapes *lt, uint64_t h, const ism_tape *t)
{
    if (lt->n >= lt->max_n || lt->bytes + tape_bytes(t) > ISM_OCTREE_TAPE_BYTES ||
        !index_room(lt) || !ism_grow((void **)&lt->v, &lt->cap, lt->n + 1, sizeof *lt->v, 16))
        return 0;
    ism_tape *c = copy_of(t);
    if (!c)
        return 0;
    lt->v[lt->n++] = c;
    lt->bytes += tape_bytes(c);
    put(lt, h, (unsigned)lt->n);
    return (unsigned)lt->n;
}

bool ism_leaf_tapes_init(ism_leaf_tapes *lt, const ism_octree *previous)
{
    memset(lt, 0, sizeof *lt);
    lt->max_n = ISM_OCTREE_TAPES;
    pthread_mutex_init(&lt->lock, NULL);
    size_t n = previous ? previous->ntapes : 0;
    for (size_t k = 0; k < n; k++) {
        const ism_tape *t = previous->tapes[k];
        if (add(lt, hash_of(t), t) != k + 1)
            return false;
    }
    return true;
}

unsigned ism_leaf_tapes_number(ism_leaf_tapes *lt, ism_leaf_tapes_cache *cache,
                               const ism_tape *t)
{
    uint64_t h = hash_of(t);
    ism_leaf_tape_hit *e = &cache->e[h % ISM_LEAF_TAPES_CACHE];
    if (e->tape && e->hash == h && ism_leaf_tapes_same(e->tape, t))
        return e->number;
    pthread_mutex_lock(&lt->lock);
    unsigned k = lt->index_cap ? slot_of(lt, h, t)->number : 0;
    if (!k)
        k = add(lt, h, t);
    const ism_tape *kept = k ? lt->v[k - 1] : NULL;
    pthread_mutex_unlock(&lt->lock);
    if (k)
        *e = (ism_leaf_tape_hit){h, kept, k};
    return k;
}

void ism_leaf_tapes_give(ism_leaf_tapes *lt, ism_octree *tree)
{
    tree->tapes = lt->v;
    tree->ntapes = lt->n;
    lt->v = NULL;
    lt->n = lt->cap = 0;
}

void ism_leaf_tapes_free(ism_leaf_tapes *lt)
{
    for (size_t k = 0; k < lt->n; k++)
        ism_tape_free(lt->v[k]);
    free(lt->v);
    free(lt->index);
    lt->v = NULL;
    lt->index = NULL;
    lt->n = lt->cap = lt->index_cap = 0;
    pthread_mutex_destroy(&lt->lock);
}
