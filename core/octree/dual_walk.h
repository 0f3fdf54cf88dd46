/* dual_walk.h — the dual mesher's tree walk (dual_tree.h's state): the quads round every
 * crossed minimal edge of the octree's leaves, with the memo of the last round's put-off
 * calls. */
#ifndef ISM_DUAL_WALK_H
#define ISM_DUAL_WALK_H

#include "core/octree/dual_tree.h"

/* The round's quads into d->q: the walk's top levels on this thread, the calls below them
 * on the pool — but for those the last round's memo holds — their quads joined in the
 * calls' order (the same on any number of threads), and kept as the next round's memo.
 * Out of memory: d->nomem; a crossed edge without a vertex: the mesh declined. */
void ism_dual_make_quads(dual *d);

/* The memo's quads and calls freed (the struct left for the caller to zero or refill). */
void ism_dual_walk_memo_free(walk_memo *m);

#endif
