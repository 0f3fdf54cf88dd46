/* leaf_tapes.c — the table of the leaves' shortened tapes (leaf_tapes.h). */
#include "core/octree/leaf_tapes.h"

#include <stdlib.h>
#include <string.h>

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

/* Field by field: an instruction's padding bytes are not part of it. */
static bool same_tape(const ism_tape *a, const ism_tape *b)
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

bool ism_leaf_tapes_init(ism_leaf_tapes *lt, const ism_octree *previous)
{
    memset(lt->v, 0, sizeof lt->v);
    atomic_init(&lt->n, 0);
    pthread_mutex_init(&lt->lock, NULL);
    size_t n = previous ? previous->ntapes : 0;
    for (size_t k = 0; k < n; k++)
        if (!(lt->v[k] = copy_of(previous->tapes[k])))
            return false;
    atomic_store(&lt->n, n);
    return true;
}

/* The number of the entry among v[from..n) equal to t, or 0. */
static unsigned find(const ism_leaf_tapes *lt, const ism_tape *t, size_t from, size_t n)
{
    for (size_t k = from; k < n; k++)
        if (same_tape(lt->v[k], t))
            return (unsigned)k + 1;
    return 0;
}

unsigned ism_leaf_tapes_number(ism_leaf_tapes *lt, const ism_tape *t)
{
    size_t n = atomic_load_explicit(&lt->n, memory_order_acquire);
    unsigned k = find(lt, t, 0, n);
    if (k)
        return k;
    pthread_mutex_lock(&lt->lock);
    size_t now = atomic_load_explicit(&lt->n, memory_order_relaxed);
    k = find(lt, t, n, now); /* added by another thread since */
    if (!k && now < ISM_OCTREE_TAPES && (lt->v[now] = copy_of(t))) {
        atomic_store_explicit(&lt->n, now + 1, memory_order_release);
        k = (unsigned)now + 1;
    }
    pthread_mutex_unlock(&lt->lock);
    return k;
}

void ism_leaf_tapes_give(ism_leaf_tapes *lt, ism_octree *tree)
{
    size_t n = atomic_load(&lt->n);
    memcpy(tree->tapes, lt->v, sizeof lt->v);
    tree->ntapes = n;
    memset(lt->v, 0, sizeof lt->v);
    atomic_store(&lt->n, 0);
}

void ism_leaf_tapes_free(ism_leaf_tapes *lt)
{
    for (size_t k = 0; k < ISM_OCTREE_TAPES; k++)
        if (lt->v[k])
            ism_tape_free(lt->v[k]);
    memset(lt->v, 0, sizeof lt->v);
    pthread_mutex_destroy(&lt->lock);
}
