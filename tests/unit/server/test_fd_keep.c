/* test_fd_keep.c — the table of kept files (server/common/fd_keep.h): a borrow reads the file
 * kept under its name (the newest put), names do not mix, a dropped name and a freed table
 * hold no descriptor; a borrow lends the table's own descriptor, which stays open through a
 * drop, a take-over or the table's end until the last borrower gives it back. */
#include <criterion/criterion.h>
#include <dirent.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "server/common/fd_keep.h"

#define NAME_A "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa.drc"
#define NAME_B "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef.drc"

/* The number of descriptors this process holds (/proc/self/fd, less the listing's own). */
static int open_descriptors(void)
{
    DIR *d = opendir("/proc/self/fd");
    cr_assert_not_null(d);
    int n = 0;
    for (struct dirent *e; (e = readdir(d));)
        n += e->d_name[0] != '.';
    closedir(d);
    return n - 1;
}

/* A temporary file holding text, open for reading; unlinked at once (the descriptor keeps it). */
static int temp_file(const char *text)
{
    char path[] = "/tmp/ism_fd_keep_XXXXXX";
    int fd = mkstemp(path);
    cr_assert_geq(fd, 0);
    cr_assert_eq(write(fd, text, strlen(text)), (ssize_t)strlen(text));
    unlink(path);
    return fd;
}

static void assert_reads(int fd, const char *text)
{
    char buf[64] = {0};
    cr_assert_eq(pread(fd, buf, sizeof buf - 1, 0), (ssize_t)strlen(text));
    cr_assert_str_eq(buf, text);
}

/* name's kept descriptor, borrowed and given back at once (-1: none kept); reads it as text
 * when text is not NULL. */
static int borrow_reads(ism_fd_keep *k, const char *name, const char *text)
{
    ism_fd_lease *l;
    int fd = ism_fd_keep_borrow(k, name, &l);
    cr_assert_eq(fd < 0, l == NULL, "%s: fd %d, lease %p", name, fd, (void *)l);
    if (text)
        assert_reads(fd, text);
    ism_fd_keep_give_back(l);
    return fd;
}

Test(fd_keep, a_borrow_reads_the_kept_file_and_names_do_not_mix)
{
    int before = open_descriptors();
    ism_fd_keep *k = ism_fd_keep_new();
    cr_assert_not_null(k);
    cr_assert_eq(borrow_reads(k, NAME_A, NULL), -1);
    int a = temp_file("first file");
    ism_fd_keep_put(k, NAME_A, a);
    close(a); /* the table holds its own */
    cr_assert_eq(borrow_reads(k, NAME_B, NULL), -1);
    int got = borrow_reads(k, NAME_A, "first file");
    cr_assert_geq(got, 0);
    cr_assert(fcntl(got, F_GETFD) & FD_CLOEXEC);
    cr_assert_eq(borrow_reads(k, NAME_A, "first file"), got); /* given back: still kept */
    /* a newer file under the same name replaces the kept one */
    int b = temp_file("second file");
    ism_fd_keep_put(k, NAME_A, b);
    close(b);
    borrow_reads(k, NAME_A, "second file");
    cr_assert_eq(open_descriptors(), before + 1); /* the first one closed */
    ism_fd_keep_drop(k, NAME_A);
    cr_assert_eq(borrow_reads(k, NAME_A, NULL), -1);
    ism_fd_keep_free(k);
    cr_assert_eq(open_descriptors(), before);
}

Test(fd_keep, freeing_closes_every_kept_file)
{
    int before = open_descriptors();
    ism_fd_keep *k = ism_fd_keep_new();
    char name[80];
    for (int i = 0; i < 200; i++) { /* more names than slots: taken-over slots close theirs */
        snprintf(name, sizeof name, "%064d.drc", i);
        int fd = temp_file(name);
        ism_fd_keep_put(k, name, fd);
        close(fd);
    }
    cr_assert_gt(open_descriptors(), before);
    ism_fd_keep_free(k);
    cr_assert_eq(open_descriptors(), before);
}

Test(fd_keep, a_lent_descriptor_outlives_its_slot_until_the_last_give_back)
{
    int before = open_descriptors();
    ism_fd_keep *k = ism_fd_keep_new();
    ism_fd_lease *none = (ism_fd_lease *)&before;
    cr_assert_eq(ism_fd_keep_borrow(k, NAME_A, &none), -1);
    cr_assert_null(none);
    int a = temp_file("lent file");
    ism_fd_keep_put(k, NAME_A, a);
    close(a);
    int kept = open_descriptors();
    cr_assert_eq(kept, before + 1);
    ism_fd_lease *l1, *l2;
    int b1 = ism_fd_keep_borrow(k, NAME_A, &l1), b2 = ism_fd_keep_borrow(k, NAME_A, &l2);
    cr_assert_not_null(l1);
    cr_assert_geq(b1, 0);
    cr_assert_eq(b1, b2); /* the kept descriptor itself: no new one */
    cr_assert_eq(open_descriptors(), kept);
    cr_assert(fcntl(b1, F_GETFD) & FD_CLOEXEC);
    ism_fd_lease *other;
    cr_assert_eq(ism_fd_keep_borrow(k, NAME_B, &other), -1);
    /* evicted while lent (the pruner drops the name): both borrowers still read it */
    ism_fd_keep_drop(k, NAME_A);
    cr_assert_eq(borrow_reads(k, NAME_A, NULL), -1);
    assert_reads(b1, "lent file");
    ism_fd_keep_give_back(l1);
    assert_reads(b2, "lent file");
    cr_assert_eq(open_descriptors(), kept);
    ism_fd_keep_give_back(l2); /* the last: closed */
    cr_assert_eq(open_descriptors(), before);
    /* a slot taken over by a newer file while lent, and a table freed while lent */
    int c = temp_file("third file");
    ism_fd_keep_put(k, NAME_A, c);
    close(c);
    ism_fd_lease *l3;
    int b3 = ism_fd_keep_borrow(k, NAME_A, &l3);
    int d = temp_file("fourth file");
    ism_fd_keep_put(k, NAME_A, d);
    close(d);
    assert_reads(b3, "third file");
    ism_fd_lease *l4;
    int b4 = ism_fd_keep_borrow(k, NAME_A, &l4);
    assert_reads(b4, "fourth file");
    ism_fd_keep_free(k);
    assert_reads(b3, "third file");
    assert_reads(b4, "fourth file");
    ism_fd_keep_give_back(l3);
    ism_fd_keep_give_back(l4);
    ism_fd_keep_give_back(NULL);
    cr_assert_eq(open_descriptors(), before);
}
