/* preset_tape.c — see preset_tape.h. */
#include "tests/unit/proto/preset_tape.h"

#include <stdio.h>

enum { MAX_PARAMS = 16 };

ism_tape *test_preset_tape(const ism_preset *p, ism_error *err)
{
    ism_param params[MAX_PARAMS];
    if (p->nparams > MAX_PARAMS) {
        snprintf(err->message, sizeof err->message, "%s: %zu parameters", p->name, p->nparams);
        return NULL;
    }
    for (size_t i = 0; i < p->nparams; i++)
        params[i] = (ism_param){ p->params[i].name, p->params[i].value };
    return ism_tape_compile(p->expr, params, p->nparams, p->lets, p->nlets, NULL, err);
}
