/* test_generated_files.c — files the repository holds as a generator's output are that output:
 * core/eval/sincos_table.h is what tests/unit/core/sincos_coeffs.py --write writes (its
 * --check mode compares, with mpmath alone, no libm). A hand edit of a constant or a row, or a
 * generator change not followed by --write, fails here. Skipped where python3 or mpmath is
 * missing (the generator needs them; the build does not). Here rather than in unit_core:
 * running a program is spawn_for_tests.c's, which unit_proto links. */
#include <criterion/criterion.h>
#include <stdlib.h>

#include "tests/unit/proto/spawn_for_tests.h"

/* generous: the generator takes ~0.1 s of CPU (mpmath at 80 digits, 256 rows) */
#define GENERATOR_TIMEOUT_S 120

Test(generated_files, sincos_table_is_its_generators_output)
{
    char *probe[] = {"python3", "-c", "import mpmath", NULL};
    if (test_run(probe, GENERATOR_TIMEOUT_S, NULL, NULL) != 0)
        cr_skip_test("python3 with mpmath is not installed");
    char *argv[] = {"python3", "tests/unit/core/sincos_coeffs.py", "--check", NULL};
    char *out = NULL;
    int rc = test_run(argv, GENERATOR_TIMEOUT_S, &out, NULL);
    cr_assert_eq(rc, 0, "core/eval/sincos_table.h is not what sincos_coeffs.py --write writes "
                        "(run from the repository root):\n%s", out ? out : "");
    free(out);
}
