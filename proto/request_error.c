/* request_error.c — the error document every non-200 answer carries:
 * {"error": {"code": "...", "message": "...", "path": "$.x", "line": L, "column": C}}
 * (path, line and column only when known). */
#include "proto/request.h"
#include "proto/json_writer.h"

char *ism_req_error_json(const ism_req_error *err, size_t *len)
{
    ism_jw w;
    ism_jw_init(&w);
    ism_jw_object(&w);
    ism_jw_key(&w, "error");
    ism_jw_object(&w);
    ism_jw_key(&w, "code");
    ism_jw_string(&w, err->code[0] ? err->code : "internal");
    ism_jw_key(&w, "message");
    ism_jw_string(&w, err->message);
    if (err->path[0]) {
        ism_jw_key(&w, "path");
        ism_jw_string(&w, err->path);
    }
    if (err->line > 0) {
        ism_jw_key(&w, "line");
        ism_jw_int(&w, err->line);
    }
    if (err->column > 0) {
        ism_jw_key(&w, "column");
        ism_jw_int(&w, err->column);
    }
    ism_jw_object_end(&w);
    ism_jw_object_end(&w);
    return ism_jw_take(&w, len);
}
