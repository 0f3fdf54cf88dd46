/* shorten_memo.h — the shortenings a level build has met (level_build.c): a tape's number in
 * the task's table and the choices an interval pass recorded at its min/max instructions
 * (shorten.c) name the tape they shorten it to, so a child whose pass records choices met
 * before below the same tape takes that tape's number without the backward pass, the copy
 * and the table's lookup. The shortening is a function of the tape and those choices alone
 * (ism_tape_shorten_recorded reads no other), so the number is the one they would give. */
#ifndef ISM_SHORTEN_MEMO_H
#define ISM_SHORTEN_MEMO_H

#include "core/expr/expr.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Min/max instructions a tape may have for its choices to be a key: two bits each in 64. A
 * tape with more is shortened every time. */
#define ISM_SHORTEN_MEMO_MAX_KINKS 32

typedef struct ism_shorten_memo_tape ism_shorten_memo_tape;
typedef struct ism_shorten_memo_entry ism_shorten_memo_entry;

/* Zeroed: empty. */
typedef struct ism_shorten_memo {
    ism_shorten_memo_tape *tape; /* by tape number (0: f's own) */
    size_t tape_cap;
    uint32_t *at; /* the tapes' min/max positions, each tape's together */
    size_t nat, at_cap;
    ism_shorten_memo_entry *e; /* what each choice key met gave, in lists by tape */
    size_t ne, e_cap;
} ism_shorten_memo;

/* What ism_shorten_memo_get finds. */
enum ism_shorten_memo_found {
    ISM_SHORTEN_MEMO_UNKEYED = -1, /* t has more than ISM_SHORTEN_MEMO_MAX_KINKS min/max, or
                                      out of memory: shorten it */
    ISM_SHORTEN_MEMO_MISS = 0,     /* *key set, not met yet: shorten, then add */
    ISM_SHORTEN_MEMO_HIT = 1       /* *to set: the number met before */
};

/* The key of the choices choice[0, t->len) holds for tape t, number id (its min/max
 * positions found on the first call for id; t must be the same tape every time: asserted of
 * its length), and the number that key gave below id if met (ism_shorten_memo_add). */
enum ism_shorten_memo_found ism_shorten_memo_get(ism_shorten_memo *m, uint32_t id,
                                                 const ism_tape *t, const uint8_t *choice,
                                                 uint64_t *key, uint32_t *to);

/* Records that key below tape id gives tape number `to`; false when out of memory (the memo
 * is then as it was). */
bool ism_shorten_memo_add(ism_shorten_memo *m, uint32_t id, uint64_t key, uint32_t to);

void ism_shorten_memo_free(ism_shorten_memo *m);

#endif
