/* fuzz_replay.h — replays committed fuzz inputs (a seed corpus or the regression inputs of
 * one target) through the target's check function, for the regression tests in
 * tests/unit/{core,proto}/test_fuzz_regressions.c. Directories are relative to the
 * repository root, where the test runner starts the unit tests. */
#ifndef ISM_FUZZ_REPLAY_H
#define ISM_FUZZ_REPLAY_H

#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef int (*fuzz_target_fn)(const uint8_t *data, size_t size);

static inline int fuzz_replay_visible(const struct dirent *e)
{
    return e->d_name[0] != '.';
}

/* Runs every file of dir (in name order) through fn, naming the file in `current` first so
 * that a failing check can say which input broke it. Returns the number of files, or -1
 * when dir cannot be read (a missing directory counts as empty when may_be_missing). */
static inline long fuzz_replay_dir(const char *dir, fuzz_target_fn fn, char *current,
                                   size_t cap, int may_be_missing)
{
    struct dirent **names = NULL;
    int n = scandir(dir, &names, fuzz_replay_visible, alphasort);
    if (n < 0)
        return may_be_missing ? 0 : -1;
    long replayed = 0;
    for (int i = 0; i < n; i++) {
        snprintf(current, cap, "%s/%s", dir, names[i]->d_name);
        free(names[i]);
        FILE *f = fopen(current, "rb");
        if (!f) {
            replayed = -1;
            continue;
        }
        unsigned char *data = NULL;
        size_t len = 0, cap_data = 0;
        for (;;) {
            if (len == cap_data) {
                cap_data = cap_data ? 2 * cap_data : 4096;
                unsigned char *d = realloc(data, cap_data);
                if (!d)
                    break;
                data = d;
            }
            size_t got = fread(data + len, 1, cap_data - len, f);
            len += got;
            if (got == 0)
                break;
        }
        fclose(f);
        fn(data ? data : (const uint8_t *)"", len);
        free(data);
        if (replayed >= 0)
            replayed++;
    }
    free(names);
    return replayed;
}

#endif
