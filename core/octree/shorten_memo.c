/* shorten_memo.c — the shortenings a level build has met, by tape number and the choices at
 * the tape's min/max (shorten_memo.h): each number's min/max positions, found once, and its
 * short list of keys met (a list: a tape's keys are few, 3 to the power of its undecided
 * min/max at most, and Barth's sextic and the gyroid ball have one max). */
#include "core/octree/shorten_memo.h"
#include "core/expr/tape.h"
#include "core/util/grow.h"

#include <assert.h>
#include <string.h>

enum { TAPE_UNKNOWN = 0, TAPE_KEYED = 1, TAPE_UNKEYED = 2 };

struct ism_shorten_memo_tape {
    uint32_t at;    /* its first min/max position in m->at */
    uint8_t n;      /* how many */
    uint8_t state;  /* TAPE_* */
    uint32_t first; /* 1 + its first entry in m->e (0: none) */
    uint32_t len;   /* its length (low 32 bits): the check that each call names the same tape */
};

struct ism_shorten_memo_entry {
    uint64_t key;
    uint32_t to;
    uint32_t next; /* 1 + the tape's next entry (0: none) */
};

/* Tape id's slot, room made (zeroed) up to it. */
static ism_shorten_memo_tape *slot(ism_shorten_memo *m, uint32_t id)
{
    if ((size_t)id >= m->tape_cap) {
        size_t cap = m->tape_cap;
        if (!ism_grow((void **)&m->tape, &cap, (size_t)id + 1, sizeof *m->tape, 64))
            return NULL;
        memset(m->tape + m->tape_cap, 0, (cap - m->tape_cap) * sizeof *m->tape);
        m->tape_cap = cap;
    }
    return &m->tape[id];
}

/* Finds t's min/max positions into m->at (state TAPE_KEYED), or TAPE_UNKEYED past the
 * limit; false when out of memory. */
static bool learn(ism_shorten_memo *m, ism_shorten_memo_tape *mt, const ism_tape *t)
{
    mt->len = (uint32_t)t->len;
    size_t n = 0;
    for (size_t i = 0; i < t->len; i++)
        n += ism_op_is_min_max(t->code[i].op);
    if (n > ISM_SHORTEN_MEMO_MAX_KINKS || t->len > UINT32_MAX) {
        mt->state = TAPE_UNKEYED;
        return true;
    }
    if (!ism_grow((void **)&m->at, &m->at_cap, m->nat + n, sizeof *m->at, 64))
        return false;
    mt->at = (uint32_t)m->nat;
    mt->n = (uint8_t)n;
    for (size_t i = 0; i < t->len; i++)
        if (ism_op_is_min_max(t->code[i].op))
            m->at[m->nat++] = (uint32_t)i;
    mt->state = TAPE_KEYED;
    return true;
}

enum ism_shorten_memo_found ism_shorten_memo_get(ism_shorten_memo *m, uint32_t id,
                                                 const ism_tape *t, const uint8_t *choice,
                                                 uint64_t *key, uint32_t *to)
{
    ism_shorten_memo_tape *mt = (size_t)id < m->tape_cap ? &m->tape[id] : slot(m, id);
    if (!mt || (mt->state == TAPE_UNKNOWN && !learn(m, mt, t)))
        return ISM_SHORTEN_MEMO_UNKEYED;
    assert(mt->len == (uint32_t)t->len && "id names another tape than on its first call");
    if (mt->state != TAPE_KEYED)
        return ISM_SHORTEN_MEMO_UNKEYED;
    uint64_t k = 0;
    const uint32_t *at = m->at + mt->at;
    for (unsigned j = 0; j < mt->n; j++)
        k |= (uint64_t)(choice[at[j]] & 3u) << (2 * j); /* shorten.c's choice: 0, 1 or 2 */
    *key = k;
    for (uint32_t e = mt->first; e; e = m->e[e - 1].next)
        if (m->e[e - 1].key == k) {
            *to = m->e[e - 1].to;
            return ISM_SHORTEN_MEMO_HIT;
        }
    return ISM_SHORTEN_MEMO_MISS;
}

bool ism_shorten_memo_add(ism_shorten_memo *m, uint32_t id, uint64_t key, uint32_t to)
{
    ism_shorten_memo_tape *mt = slot(m, id);
    if (!mt || m->ne >= UINT32_MAX ||
        !ism_grow((void **)&m->e, &m->e_cap, m->ne + 1, sizeof *m->e, 64))
        return false;
    m->e[m->ne++] = (ism_shorten_memo_entry){key, to, mt->first};
    mt->first = (uint32_t)m->ne;
    return true;
}

void ism_shorten_memo_free(ism_shorten_memo *m)
{
    free(m->tape);
    free(m->at);
    free(m->e);
    memset(m, 0, sizeof *m);
}
