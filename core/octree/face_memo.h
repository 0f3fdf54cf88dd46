/* face_memo.h — one thread's memo of what the hidden-piece search finds on what nodes
 * share (octree_build.c hides_piece): verdicts on faces (root pairs on edges are
 * cell_cache.h's ism_pair_entry).
 *
 * A face whose four corners share a sign is searched for an
 * island by each of the two nodes of one level beside it; the second finds the first's
 * verdict here. An entry holds the face's place on the lattice and the number of the tape
 * that searched it (leaf_tapes.h: equal numbers, equal code), and the search is a function
 * of those alone (the face's corners are lattice points, its box their coordinates), so a
 * hit answers what the search would: meshes are the same bit for bit. Direct-mapped: a
 * face overwrites the entry of an earlier face with the same hash. */
#ifndef ISM_FACE_MEMO_H
#define ISM_FACE_MEMO_H

#include <stdbool.h>
#include <stdint.h>

/* Entries per thread (16 bytes each): the faces of a subtree's last few thousand would-be
 * leaves, the neighbour across a face being visited soon after (siblings) or one subtree
 * later. */
#define ISM_FACE_MEMO_BITS 12

typedef struct ism_face_memo_entry {
    uint64_t where;  /* the face's lattice point (ism_face_memo_where); 0: empty */
    uint32_t what;   /* level, axis and tape number (ism_face_memo_what) */
    uint8_t verdict; /* the caller's */
} ism_face_memo_entry;

typedef struct ism_face_memo {
    ism_face_memo_entry e[1u << ISM_FACE_MEMO_BITS];
} ism_face_memo; /* all zero: empty */

/* The face of a node at lattice origin org, `axis` the axis it is normal to, `plane` its
 * lattice coordinate along it (org[axis] or org[axis] + the node's size); never 0. */
uint64_t ism_face_memo_where(const int32_t org[3], int axis, int32_t plane);

/* The node's level, the axis, and the number of the tape searching the face (0: the
 * build's own tape). */
uint32_t ism_face_memo_what(int level, int axis, unsigned tape_number);

/* The verdict kept for (where, what), if any. */
bool ism_face_memo_get(const ism_face_memo *m, uint64_t where, uint32_t what,
                       uint8_t *verdict);

void ism_face_memo_put(ism_face_memo *m, uint64_t where, uint32_t what, uint8_t verdict);

#endif
