/* routes_static.c — the viewer (everything outside /v1/, from --web-root) and three.js under
 * /vendor/three/ (only build/ and examples/jsm/ of web/node_modules/three). Files go out with
 * sendfile (MHD_create_response_from_fd), a validator ETag (size and mtime) and 304 on
 * If-None-Match; anything the path rules refuse is a plain 404. */
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "server/isomeshd/http_types.h"
#include "server/isomeshd/respond.h"
#include "server/isomeshd/routes.h"

static enum MHD_Result plain_404(ismd_req *r)
{
    return ismd_respond_error(r, 404, "not_found", "no such file");
}

enum MHD_Result ismd_route_static(ismd_req *r)
{
    ismd_server *s = r->srv;
    const ismd_static *root;
    const char *rel;
    const char *cache_control;
    if (r->route == ISMD_R_VENDOR) {
        root = &s->vendor;
        rel = r->path + strlen("/vendor/three/");
        if (strncmp(rel, "build/", 6) != 0 && strncmp(rel, "examples/jsm/", 13) != 0)
            return plain_404(r);
        cache_control = "public, max-age=86400";
    } else {
        root = &s->web;
        rel = r->path + 1;
        if (!strncmp(rel, "node_modules", 12) && (rel[12] == '/' || rel[12] == 0))
            return plain_404(r); /* only through /vendor/three/ */
        cache_control = "no-cache";
    }
    /* r->path is a copy truncated to its buffer: refuse anything that was cut. */
    if (strlen(r->path) >= sizeof r->path - 1)
        return plain_404(r);
    char checked[1100];
    if (!ismd_static_path_ok(rel, checked, sizeof checked))
        return plain_404(r);
    int fd;
    struct stat st;
    const char *name;
    if (ismd_static_open_file(root, checked, &fd, &st, &name) != 0)
        return plain_404(r);
    char etag[64];
    snprintf(etag, sizeof etag, "\"%llx-%llx\"", (unsigned long long)st.st_size,
             (unsigned long long)st.st_mtim.tv_sec * 1000000000ULL + (unsigned long long)st.st_mtim.tv_nsec);
    const char *inm = ismd_header(r, MHD_HTTP_HEADER_IF_NONE_MATCH);
    struct MHD_Response *resp;
    unsigned status;
    if (inm && strstr(inm, etag)) {
        close(fd);
        resp = MHD_create_response_from_buffer(0, "", MHD_RESPMEM_PERSISTENT);
        status = 304;
    } else {
        resp = MHD_create_response_from_fd((uint64_t)st.st_size, fd);
        if (!resp) {
            close(fd);
            return MHD_NO;
        }
        MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, ismd_mime_type(name));
        r->bytes = (size_t)st.st_size;
        status = 200;
    }
    MHD_add_response_header(resp, MHD_HTTP_HEADER_ETAG, etag);
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, cache_control);
    return ismd_send(r, status, resp);
}
