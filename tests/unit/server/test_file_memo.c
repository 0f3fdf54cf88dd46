/* test_file_memo.c — the memo of checked files (server/common/file_memo.h): a check stands
 * only while the file's identity (device, inode, size, change time) is the one it was checked
 * with, a file changed moments before its check is not remembered (longer when its file
 * system may keep whole seconds), and names do not mix. */
#include <criterion/criterion.h>
#include <stdbool.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "server/common/file_memo.h"

#define NAME_A "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa.stl"
#define NAME_B "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef.stl"

/* An identity whose change time lies age_ms milliseconds in the past (a whole second when
 * whole: its nanoseconds 0). */
static struct stat identity_ms(long ino, long long size, long long age_ms, bool whole)
{
    struct stat st;
    memset(&st, 0, sizeof st);
    struct timespec now;
    clock_gettime(CLOCK_REALTIME, &now);
    long long ns = (long long)now.tv_sec * 1000000000LL + now.tv_nsec - age_ms * 1000000LL;
    if (whole)
        ns -= ns % 1000000000LL;
    st.st_dev = 3;
    st.st_ino = (ino_t)ino;
    st.st_size = (off_t)size;
    st.st_ctim.tv_sec = (time_t)(ns / 1000000000LL);
    st.st_ctim.tv_nsec = (long)(ns % 1000000000LL);
    if (!whole && st.st_ctim.tv_nsec == 0)
        st.st_ctim.tv_nsec = 1;
    return st;
}

/* An identity whose change time lies age_s seconds in the past. */
static struct stat identity(long ino, long long size, int age_s)
{
    struct stat st;
    memset(&st, 0, sizeof st);
    struct timespec now;
    clock_gettime(CLOCK_REALTIME, &now);
    st.st_dev = 3;
    st.st_ino = (ino_t)ino;
    st.st_size = (off_t)size;
    st.st_ctim.tv_sec = now.tv_sec - age_s;
    st.st_ctim.tv_nsec = now.tv_nsec;
    return st;
}

Test(file_memo, a_check_stands_only_for_the_identity_it_was_made_with)
{
    ism_file_memo *m = ism_file_memo_new();
    cr_assert_not_null(m);
    struct stat st = identity(7, 1 << 20, 10);
    cr_assert_not(ism_file_memo_holds(m, NAME_A, &st));
    ism_file_memo_put(m, NAME_A, &st);
    cr_assert(ism_file_memo_holds(m, NAME_A, &st));
    cr_assert_not(ism_file_memo_holds(m, NAME_B, &st), "another name");
    struct stat other = st;
    other.st_ino = 8; /* replaced by another file (a rename over it) */
    cr_assert_not(ism_file_memo_holds(m, NAME_A, &other));
    other = st;
    other.st_size++; /* appended to */
    cr_assert_not(ism_file_memo_holds(m, NAME_A, &other));
    other = st;
    other.st_ctim.tv_nsec = (other.st_ctim.tv_nsec + 1) % 1000000000; /* written in place */
    cr_assert_not(ism_file_memo_holds(m, NAME_A, &other));
    other = st;
    other.st_dev = 4;
    cr_assert_not(ism_file_memo_holds(m, NAME_A, &other));
    ism_file_memo_free(m);
}

Test(file_memo, a_file_changed_moments_before_its_check_is_checked_again)
{
    ism_file_memo *m = ism_file_memo_new();
    struct stat fresh = identity(9, 4096, 0);
    ism_file_memo_put(m, NAME_B, &fresh);
    cr_assert_not(ism_file_memo_holds(m, NAME_B, &fresh));
    struct stat settled = identity(9, 4096, 3);
    ism_file_memo_put(m, NAME_B, &settled);
    cr_assert(ism_file_memo_holds(m, NAME_B, &settled));
    ism_file_memo_free(m);
}

/* A change time in nanoseconds may be 5 ticks old (the clock behind file times is a tick
 * late at most); a whole-second one may share its second (or FAT's two) with a later change:
 * 3 s. */
Test(file_memo, how_long_a_change_keeps_a_file_unsettled)
{
    struct stat st = identity_ms(1, 10, 0, false);
    cr_assert_not(ism_file_memo_settled(&st), "changed now");
    st = identity_ms(1, 10, 5, false);
    cr_assert_not(ism_file_memo_settled(&st), "a tick ago");
    st = identity_ms(1, 10, 200, false);
    cr_assert(ism_file_memo_settled(&st), "200 ms ago, nanosecond times");
    st = identity_ms(1, 10, 1000, true);
    cr_assert_not(ism_file_memo_settled(&st), "1-2 s ago, whole seconds");
    st = identity_ms(1, 10, 1800, true);
    cr_assert_not(ism_file_memo_settled(&st), "1.8-2.8 s ago, whole seconds");
    st = identity_ms(1, 10, 4000, true);
    cr_assert(ism_file_memo_settled(&st), "4-5 s ago, whole seconds");
}
