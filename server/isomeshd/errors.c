/* errors.c — builds the JSON error bodies of errors.h with jansson (proper escaping). */
#include "server/isomeshd/errors.h"

#include <jansson.h>
#include <stdlib.h>

ism_blob *ismd_error_json(const char *code, const char *message, const char *path)
{
    json_t *inner = json_pack("{s:s, s:s}", "code", code, "message", message);
    if (inner && path)
        json_object_set_new(inner, "path", json_string(path));
    json_t *root = inner ? json_pack("{s:o}", "error", inner) : NULL;
    char *text = root ? json_dumps(root, JSON_COMPACT) : NULL;
    json_decref(root);
    ism_blob *b = text ? ism_blob_from_str(text) : NULL;
    free(text);
    return b;
}
