/* spawn_for_tests.h — test-only: runs a program (argv, no shell) with a bounded wait and
 * collects its standard output. */
#ifndef ISM_TEST_SPAWN_H
#define ISM_TEST_SPAWN_H

#include <stddef.h>

/* Runs argv[0] (searched in PATH), waits at most timeout_s seconds (then kills it). Returns
 * the exit status (or -1 when it could not run or was killed); *out gets its stdout
 * (malloc'd, NUL-terminated) when out is not NULL. */
int test_run(char *const argv[], int timeout_s, char **out, size_t *len);

/* Writes bytes to a fresh file under /tmp; returns its malloc'd path (suffix appended). */
char *test_write_temp(const void *data, size_t len, const char *suffix);

#endif
