/* server_timing.h — the pipeline's own phases for a response's Server-Timing header: the
 * "phase;dur=ms" pairs of the stats JSON's "timings_ms" object (a flat object of numbers). */
#ifndef ISMD_SERVER_TIMING_H
#define ISMD_SERVER_TIMING_H

#include <stddef.h>

#include "server/common/blob.h"

/* Writes "a;dur=1.000, b;dur=2.500" for stats' timings (the total left out: the daemon adds
 * its own; names that are not tokens skipped) into out, whole entries only; "" when stats
 * has none. */
void ismd_server_timing(const ism_blob *stats, char *out, size_t cap);

#endif
