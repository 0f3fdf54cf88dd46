/* test_eval_surfaces.c — the surfaces of /work/shared/surfaces.json as test data (no tests
 * of its own), and the shared random generator. */
#include <criterion/criterion.h>
#include <stdlib.h>
#include <string.h>

#include "test_eval_surfaces.h"

#define KUMMER_LETS                                                                     \
    { { "lambda", "(3*mu2 - 1)/(3 - mu2)" }, { "p", "w - z - sqrt(2)*x" },             \
      { "q", "w - z + sqrt(2)*x" }, { "r", "w + z + sqrt(2)*y" },                      \
      { "s", "w + z - sqrt(2)*y" } }

const test_surface TEST_SURFACES[] = {
    { "sphere", "x^2 + y^2 + z^2 - r^2", { { "r", 1 } }, 1, { { 0 } }, 0,
      { -1.5, -1.5, -1.5, 1.5, 1.5, 1.5 }, 1 },
    { "torus", "(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)",
      { { "R", 1 }, { "r", 0.3 } }, 2, { { 0 } }, 0, { -1.5, -1.5, -1.5, 1.5, 1.5, 1.5 }, 1 },
    { "pretzel-genus2", "(x*(x-1)^2*(x-2) + y^2)^2 + z^2 - t", { { "t", 0.03 } }, 1,
      { { 0 } }, 0, { -0.5, -1.5, -1.5, 2.5, 1.5, 1.5 }, 1 },
    { "gyroid-ball",
      "max(sin(k*x)*cos(k*y) + sin(k*y)*cos(k*z) + sin(k*z)*cos(k*x), x^2 + y^2 + z^2 - 1.96)",
      { { "k", 4 } }, 1, { { 0 } }, 0, { -1.5, -1.5, -1.5, 1.5, 1.5, 1.5 }, 0 },
    { "kummer-4-nodes", "(x^2 + y^2 + z^2 - mu2)^2 - lambda*p*q*r*s",
      { { "mu2", 0.6667 }, { "w", 1 } }, 2, KUMMER_LETS, 5, { -3, -3, -3, 3, 3, 3 }, 1 },
    { "kummer-16-nodes", "(x^2 + y^2 + z^2 - mu2)^2 - lambda*p*q*r*s",
      { { "mu2", 2 }, { "w", 1 } }, 2, KUMMER_LETS, 5, { -3, -3, -3, 3, 3, 3 }, 1 },
    { "horn-cyclide",
      "(x^2 + y^2 + z^2 + a^2 - f^2 - r^2)^2 - 4*(a*x - f*r)^2 - 4*(a^2 - f^2)*y^2",
      { { "a", 10 }, { "r", 2 }, { "f", 2 } }, 3, { { 0 } }, 0,
      { -15, -16, -16, 17, 16, 16 }, 1 },
    { "klein-bottle",
      "(x^2 + y^2 + z^2 + 2*y - 1)*((x^2 + y^2 + z^2 - 2*y - 1)^2 - 8*z^2) + "
      "16*x*z*(x^2 + y^2 + z^2 - 2*y - 1)",
      { { 0 } }, 0, { { 0 } }, 0, { -4, -4, -4, 4, 4, 4 }, 1 },
    { "steiner-roman", "x^2*y^2 + y^2*z^2 + z^2*x^2 + x*y*z", { { 0 } }, 0, { { 0 } }, 0,
      { -1, -1, -1, 1, 1, 1 }, 1 },
};

const size_t TEST_NSURFACES = sizeof TEST_SURFACES / sizeof TEST_SURFACES[0];

ism_tape *test_surface_compile(const test_surface *s)
{
    ism_error err;
    char msg[256];
    ism_tape *t = ism_tape_compile(s->expr, s->params, s->nparams, s->lets, s->nlets, NULL,
                                   &err);
    cr_assert_not_null(t, "%s: %s", s->name, ism_error_format(&err, msg, sizeof msg));
    return t;
}

const test_surface *test_surface_named(const char *name)
{
    for (size_t i = 0; i < TEST_NSURFACES; i++)
        if (strcmp(TEST_SURFACES[i].name, name) == 0)
            return &TEST_SURFACES[i];
    cr_assert_fail("no test surface %s", name);
    return NULL;
}

double test_uniform(test_rng *r, double lo, double hi)
{
    uint64_t z = (r->s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return lo + (hi - lo) * ((double)(z >> 11) * 0x1p-53);
}

size_t test_scaled(size_t full)
{
    const char *q = getenv("ISOMESH_TEST_QUICK");
    return q && q[0] == '1' ? (full + 4) / 5 : full;
}
