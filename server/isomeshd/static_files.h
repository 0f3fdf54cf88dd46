/* static_files.h — files served from a directory (the viewer's web/, three.js under
 * web/node_modules/three) without ever leaving it: URL paths are checked component by
 * component (letters, digits, '.', '_', '-'; no empty, "." or ".." component, nothing hidden),
 * then opened relative to the root's descriptor with openat2(RESOLVE_BENEATH), so neither
 * "..", nor an encoded one, nor a symlink can reach outside. No directory listings. */
#ifndef ISMD_STATIC_FILES_H
#define ISMD_STATIC_FILES_H

#include <stdbool.h>
#include <stddef.h>
#include <sys/stat.h>

typedef struct ismd_static {
    int root_fd;              /* -1 when not serving */
    char root[4096];
} ismd_static;

/* Opens dir as a root (false, and root_fd -1, when it is not a readable directory). */
bool ismd_static_open(ismd_static *s, const char *dir);
void ismd_static_close(ismd_static *s);

/* Checks a URL path relative to the root ("" or "a/b.js", no leading slash); a trailing '/'
 * is allowed and means the directory's index.html. Writes the path to open into out. */
bool ismd_static_path_ok(const char *rel, char *out, size_t cap);

/* Opens rel (already checked) under the root: a regular file, or a directory's index.html.
 * Returns 0 with *fd and *st set, or 404. */
int ismd_static_open_file(const ismd_static *s, const char *rel, int *fd, struct stat *st,
                          const char **name_for_type);

/* MIME type by file name (module scripts are text/javascript, .wasm application/wasm). */
const char *ismd_mime_type(const char *name);

#endif
