/* face_memo.c — one thread's direct-mapped memo of face verdicts (see face_memo.h). */
#include "core/octree/face_memo.h"

/* Lattice coordinates take 20 bits (ISM_GRID_MAX_DEPTH 19: at most 2^19); 21 each, and
 * the top bit set so that no face is 0 (the empty entry). */
#define COORD_BITS 21

uint64_t ism_face_memo_where(const int32_t org[3], int axis, int32_t plane)
{
    uint64_t w = 1;
    for (int a = 0; a < 3; a++)
        w = (w << COORD_BITS) | (uint32_t)(a == axis ? plane : org[a]);
    return w;
}

uint32_t ism_face_memo_what(int level, int axis, unsigned tape_number)
{
    return (uint32_t)level << 18 | (uint32_t)axis << 16 | (tape_number & 0xffffu);
}

static uint32_t slot_of(uint64_t where, uint32_t what)
{
    uint64_t h = (where ^ (uint64_t)what << 40) * 0x9e3779b97f4a7c15u;
    return (uint32_t)(h >> (64 - ISM_FACE_MEMO_BITS));
}

bool ism_face_memo_get(const ism_face_memo *m, uint64_t where, uint32_t what,
                       uint8_t *verdict)
{
    const ism_face_memo_entry *e = &m->e[slot_of(where, what)];
    if (e->where != where || e->what != what)
        return false;
    *verdict = e->verdict;
    return true;
}

void ism_face_memo_put(ism_face_memo *m, uint64_t where, uint32_t what, uint8_t verdict)
{
    ism_face_memo_entry *e = &m->e[slot_of(where, what)];
    e->where = where;
    e->what = what;
    e->verdict = verdict;
}
