/* static_files.c — path checks, confined opening and MIME types for static_files.h. */
#include "server/isomeshd/static_files.h"

#include <errno.h>
#include <fcntl.h>
#include <linux/openat2.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/syscall.h>
#include <unistd.h>

bool ismd_static_open(ismd_static *s, const char *dir)
{
    s->root_fd = -1;
    s->root[0] = 0;
    if (!dir || !*dir)
        return false;
    char real[4096];
    if (!realpath(dir, real))
        return false;
    int fd = open(real, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0)
        return false;
    s->root_fd = fd;
    snprintf(s->root, sizeof s->root, "%s", real);
    return true;
}

void ismd_static_close(ismd_static *s)
{
    if (s->root_fd >= 0)
        close(s->root_fd);
    s->root_fd = -1;
}

static bool name_char(char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
           c == '.' || c == '_' || c == '-';
}

bool ismd_static_path_ok(const char *rel, char *out, size_t cap)
{
    size_t n = strlen(rel);
    if (n + sizeof "index.html" >= cap || n > 1024)
        return false;
    size_t comp_start = 0;
    for (size_t i = 0; i <= n; i++) {
        if (i < n && rel[i] != '/') {
            if (!name_char(rel[i]))
                return false; /* NUL markers, '%', '\\', spaces, controls, non-ASCII */
            continue;
        }
        size_t len = i - comp_start;
        if (len == 0 && !(i == n && (n == 0 || rel[n - 1] == '/')))
            return false; /* empty component: a doubled or leading slash */
        if (len > 0 && rel[comp_start] == '.')
            return false; /* ".", "..", hidden files */
        if (len > 255)
            return false;
        comp_start = i + 1;
    }
    memcpy(out, rel, n + 1);
    if (n == 0 || rel[n - 1] == '/')
        strcat(out, "index.html");
    return true;
}

/* openat2 confined to the root; falls back to a no-symlinks walk on kernels without it. */
static int open_beneath(int root, const char *rel, int flags)
{
    struct open_how how = {
        .flags = (unsigned long long)(flags | O_CLOEXEC),
        .resolve = RESOLVE_BENEATH | RESOLVE_NO_MAGICLINKS,
    };
    long fd = syscall(SYS_openat2, root, rel, &how, sizeof how);
    if (fd >= 0 || errno != ENOSYS)
        return (int)fd;
    /* Old kernel: walk the components refusing every symlink. */
    char buf[1100];
    snprintf(buf, sizeof buf, "%s", rel);
    int dir = dup(root);
    char *save = NULL;
    char *comp = strtok_r(buf, "/", &save);
    while (comp && dir >= 0) {
        char *next = strtok_r(NULL, "/", &save);
        int nf = next ? (O_RDONLY | O_DIRECTORY) : flags;
        int f = openat(dir, comp, nf | O_NOFOLLOW | O_CLOEXEC);
        close(dir);
        dir = f;
        comp = next;
    }
    return dir;
}

int ismd_static_open_file(const ismd_static *s, const char *rel, int *fd, struct stat *st,
                          const char **name_for_type)
{
    if (s->root_fd < 0)
        return 404;
    int f = open_beneath(s->root_fd, rel, O_RDONLY);
    if (f < 0)
        return 404;
    if (fstat(f, st) != 0) {
        close(f);
        return 404;
    }
    static __thread char index_path[1200];
    *name_for_type = rel;
    if (S_ISDIR(st->st_mode)) {
        /* "dir" without a slash: its index.html, else nothing (no listings). */
        close(f);
        snprintf(index_path, sizeof index_path, "%s/index.html", rel);
        f = open_beneath(s->root_fd, index_path, O_RDONLY);
        if (f < 0 || fstat(f, st) != 0) {
            if (f >= 0)
                close(f);
            return 404;
        }
        *name_for_type = index_path;
    }
    if (!S_ISREG(st->st_mode)) {
        close(f);
        return 404;
    }
    *fd = f;
    return 0;
}

const char *ismd_mime_type(const char *name)
{
    static const struct {
        const char *ext, *type;
    } T[] = {
        {".html", "text/html; charset=utf-8"},
        {".htm", "text/html; charset=utf-8"},
        {".js", "text/javascript; charset=utf-8"},
        {".mjs", "text/javascript; charset=utf-8"},
        {".css", "text/css; charset=utf-8"},
        {".json", "application/json"},
        {".map", "application/json"},
        {".webmanifest", "application/manifest+json"},
        {".wasm", "application/wasm"},
        {".svg", "image/svg+xml"},
        {".png", "image/png"},
        {".jpg", "image/jpeg"},
        {".jpeg", "image/jpeg"},
        {".gif", "image/gif"},
        {".webp", "image/webp"},
        {".ico", "image/x-icon"},
        {".txt", "text/plain; charset=utf-8"},
        {".md", "text/markdown; charset=utf-8"},
        {".yaml", "application/yaml"},
        {".woff", "font/woff"},
        {".woff2", "font/woff2"},
        {".ttf", "font/ttf"},
        {".glb", "model/gltf-binary"},
        {".gltf", "model/gltf+json"},
        {".drc", "application/octet-stream"},
    };
    const char *dot = strrchr(name, '.');
    const char *slash = strrchr(name, '/');
    if (dot && (!slash || dot > slash))
        for (size_t i = 0; i < sizeof T / sizeof T[0]; i++)
            if (strcasecmp(dot, T[i].ext) == 0)
                return T[i].type;
    return "application/octet-stream";
}
