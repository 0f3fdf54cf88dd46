/* test_fd_io.c — safe replacement of a whole file (server/common/fd_io.h): the new bytes and
 * the asked permissions replace the old file (a reader holding the old one keeps its old
 * bytes: the file is renamed over, not rewritten), nothing is left beside it, and a failure
 * leaves the old file whole and no temporary file behind. */
#include <criterion/criterion.h>
#include <dirent.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "server/common/fd_io.h"

/* A fresh directory; its path in dir (cap bytes). */
static void fresh_dir(char *dir, size_t cap)
{
    snprintf(dir, cap, "/tmp/isomesh-fdio-XXXXXX");
    cr_assert_not_null(mkdtemp(dir));
}

static int entries(const char *dir)
{
    DIR *d = opendir(dir);
    cr_assert_not_null(d);
    int n = 0;
    for (struct dirent *e; (e = readdir(d));)
        n += e->d_name[0] != '.';
    closedir(d);
    return n;
}

static void remove_dir(const char *dir, const char *file)
{
    char p[256];
    snprintf(p, sizeof p, "%s/%s", dir, file);
    unlink(p);
    rmdir(dir);
}

Test(fd_io, replace_gives_the_new_bytes_and_mode_by_a_rename)
{
    char dir[64], path[96], err[512];
    fresh_dir(dir, sizeof dir);
    snprintf(path, sizeof path, "%s/out.ply", dir);
    cr_assert(ism_replace_file(path, "old!", 4, 0600, err, sizeof err), "%s", err);
    int reader = open(path, O_RDONLY);
    cr_assert_geq(reader, 0);
    cr_assert(ism_replace_file(path, "brand new", 9, 0644, err, sizeof err), "%s", err);
    char *data = NULL;
    size_t len = 0;
    unsigned mode = 0;
    cr_assert_eq(ism_read_file(path, 100, &data, &len, &mode, err, sizeof err), 1, "%s", err);
    cr_assert_eq(len, 9);
    cr_assert_str_eq(data, "brand new");
    cr_assert_eq(mode & 0777, 0644);
    free(data);
    char old[8] = {0};
    cr_assert_eq(read(reader, old, sizeof old), 4, "the old file is still whole for its reader");
    cr_assert_str_eq(old, "old!");
    close(reader);
    cr_assert_eq(entries(dir), 1, "no temporary file left");
    remove_dir(dir, "out.ply");
}

Test(fd_io, a_failed_replacement_leaves_the_old_file_and_no_temporary)
{
    char dir[64], path[96], tmp[128], err[512];
    fresh_dir(dir, sizeof dir);
    snprintf(path, sizeof path, "%s/tokens", dir);
    cr_assert(ism_replace_file(path, "kept", 4, 0600, err, sizeof err), "%s", err);
    /* A temporary that cannot be written (opened read-only): the write fails. */
    snprintf(tmp, sizeof tmp, "%s.new", path);
    int fd = open(tmp, O_RDONLY | O_CREAT | O_EXCL, 0600);
    cr_assert_geq(fd, 0);
    cr_assert_not(ism_replace_file_via(fd, tmp, path, "lost", 4, 0600, err, sizeof err));
    cr_assert_not_null(strstr(err, path), "%s", err);
    cr_assert_not_null(strstr(err, "writing"), "%s", err);
    char *data = NULL;
    size_t len = 0;
    cr_assert_eq(ism_read_file(path, 100, &data, &len, NULL, err, sizeof err), 1, "%s", err);
    cr_assert_str_eq(data, "kept");
    free(data);
    cr_assert_eq(entries(dir), 1, "the temporary is removed");
    remove_dir(dir, "tokens");
}

Test(fd_io, a_directory_that_does_not_exist_is_an_error_naming_the_file)
{
    char err[512];
    cr_assert_not(ism_replace_file("/nonexistent-isomesh-dir/x.obj", "x", 1, 0644, err, sizeof err));
    cr_assert_not_null(strstr(err, "/nonexistent-isomesh-dir/x.obj"), "%s", err);
}
