/* format.c — the output formats a request can name: their names on the wire, their MIME
 * types, and the ?format= override. */
#include "proto/request.h"

#include <string.h>

static const char *const format_names[ISM_FORMAT_COUNT] = {"drc", "glb", "ply", "obj", "stl",
                                                            "png"};
static const char *const format_mimes[ISM_FORMAT_COUNT] = {
    "application/vnd.google.draco", "model/gltf-binary", "application/ply", "model/obj",
    "model/stl", "image/png"};

const char *ism_format_name(enum ism_format f)
{
    return (unsigned)f < ISM_FORMAT_COUNT ? format_names[f] : "?";
}

const char *ism_format_mime(enum ism_format f)
{
    return (unsigned)f < ISM_FORMAT_COUNT ? format_mimes[f] : "application/octet-stream";
}

const char *ism_format_mime_of(const char *name)
{
    return ism_format_mime((enum ism_format)ism_format_lookup(name));
}

int ism_format_lookup(const char *name)
{
    for (int i = 0; i < ISM_FORMAT_COUNT; i++)
        if (strcmp(format_names[i], name) == 0)
            return i;
    return -1;
}

bool ism_request_set_format(ism_request *req, const char *name, ism_req_error *err)
{
    int k = ism_format_lookup(name);
    if (k < 0)
        return ism_req_error_set(err, 400, "bad_request", "format",
                                 "unknown format (expected one of: drc, glb, ply, obj, stl, png)");
    req->format = (enum ism_format)k;
    return true;
}
