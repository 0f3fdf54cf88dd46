/* emit.h — lowering the expression graph to a tape. Internal to core/expr. */
#ifndef ISM_EMIT_H
#define ISM_EMIT_H

#include "core/expr/graph.h"
#include "core/expr/tape.h"

/* Emits the nodes reachable from root in a canonical order (depth-first, operands in the
 * graph's canonical order), constants as immediates, registers reused once dead. NULL when
 * out of memory. */
ism_tape *ism_emit_tape(const ism_graph *g, uint32_t root);

#endif
