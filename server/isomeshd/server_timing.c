/* server_timing.c — Server-Timing entries from a computation's stats (server_timing.h). */
#include "server/isomeshd/server_timing.h"

#include <jansson.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

void ismd_server_timing(const ism_blob *stats, char *out, size_t cap)
{
    out[0] = 0;
    if (!stats)
        return;
    json_t *root = json_loadb((const char *)stats->data, stats->len, 0, NULL);
    json_t *t = root ? json_object_get(root, "timings_ms") : NULL;
    size_t used = 0;
    const char *k;
    json_t *v;
    if (json_is_object(t)) {
        json_object_foreach(t, k, v) {
            if (!json_is_number(v) || !strcmp(k, "total"))
                continue; /* the daemon adds its own total */
            bool token = *k != 0;
            for (const char *c = k; *c; c++)
                if (!((*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') ||
                      (*c >= '0' && *c <= '9') || *c == '_' || *c == '-'))
                    token = false;
            if (!token)
                continue;
            int n = snprintf(out + used, cap - used, "%s%s;dur=%.3f", used ? ", " : "", k,
                             json_number_value(v));
            if (n < 0 || (size_t)n >= cap - used) {
                out[used] = 0;
                break;
            }
            used += (size_t)n;
        }
    }
    json_decref(root);
}
