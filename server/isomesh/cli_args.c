/* cli_args.c — parsing and checking the `isomesh` command's flag values (numbers, boxes,
 * depths, NAME=VALUE pairs), each failure a one-line message naming the flag. */
#include "server/isomesh/cli.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void ism_cli_run_init(ism_cli_run *run)
{
    memset(run, 0, sizeof *run);
    ism_poly_options_default(&run->options);
}

bool ism_cli_parse_double(const char *flag, const char *s, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end != '\0' || errno == ERANGE || !isfinite(v)) {
        fprintf(stderr, "isomesh: %s: '%s' is not a finite number\n", flag, s);
        return false;
    }
    *out = v;
    return true;
}

bool ism_cli_parse_int(const char *flag, const char *s, int lo, int hi, int *out)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (end == s || *end != '\0' || errno == ERANGE || v < lo || v > hi) {
        fprintf(stderr, "isomesh: %s: '%s' is not a whole number in %d..%d\n", flag, s, lo, hi);
        return false;
    }
    *out = (int)v;
    return true;
}

bool ism_cli_parse_box(const char *s, double box[6])
{
    const char *p = s;
    for (int k = 0; k < 6; k++) {
        char *end;
        errno = 0;
        box[k] = strtod(p, &end);
        if (end == p || errno == ERANGE || !isfinite(box[k]) ||
            (k < 5 && *end != ',') || (k == 5 && *end != '\0')) {
            fprintf(stderr,
                    "isomesh: --box: expected six numbers X0,Y0,Z0,X1,Y1,Z1, got '%s'\n", s);
            return false;
        }
        p = end + 1;
    }
    for (int k = 0; k < 3; k++)
        if (!(box[3 + k] > box[k])) {
            fprintf(stderr, "isomesh: --box: %c1 must be greater than %c0\n", "XYZ"[k], "XYZ"[k]);
            return false;
        }
    return true;
}

bool ism_cli_parse_depth(const char *s, int *min_depth, int *max_depth)
{
    int a, b, used = 0;
    if (sscanf(s, "%d:%d%n", &a, &b, &used) != 2 || s[used] != '\0' || a < 0 || b < a ||
        b > ISM_MAX_DEPTH_LIMIT) {
        fprintf(stderr, "isomesh: --depth: expected MIN:MAX with 0 <= MIN <= MAX <= %d, got '%s'\n",
                ISM_MAX_DEPTH_LIMIT, s);
        return false;
    }
    *min_depth = a;
    *max_depth = b;
    return true;
}

/* Splits NAME=REST; the name is malloc'd. */
static char *split_name(const char *flag, const char *s, const char **rest)
{
    const char *eq = strchr(s, '=');
    if (!eq || eq == s || eq - s > 63) {
        fprintf(stderr, "isomesh: %s: expected NAME=VALUE, got '%s'\n", flag, s);
        return NULL;
    }
    *rest = eq + 1;
    return strndup(s, (size_t)(eq - s));
}

bool ism_cli_add_param(ism_cli_run *run, const char *s)
{
    const char *rest;
    char *name = split_name("--param", s, &rest);
    double v;
    if (!name)
        return false;
    if (!ism_cli_parse_double("--param", rest, &v)) {
        free(name);
        return false;
    }
    for (size_t i = 0; i < run->nparams; i++)
        if (strcmp(run->params[i].name, name) == 0) { /* a later -p wins */
            run->params[i].value = v;
            free(name);
            return true;
        }
    ism_param *p = realloc(run->params, (run->nparams + 1) * sizeof *p);
    if (!p) {
        free(name);
        return false;
    }
    run->params = p;
    run->params[run->nparams++] = (ism_param){name, v};
    return true;
}

bool ism_cli_add_let(ism_cli_run *run, const char *s)
{
    const char *rest;
    char *name = split_name("--let", s, &rest);
    if (!name)
        return false;
    ism_let *l = realloc(run->lets, (run->nlets + 1) * sizeof *l);
    char *src = strdup(rest);
    if (!l || !src) {
        free(name);
        free(src);
        free(l == run->lets ? NULL : l);
        return false;
    }
    run->lets = l;
    run->lets[run->nlets++] = (ism_let){name, src};
    return true;
}
