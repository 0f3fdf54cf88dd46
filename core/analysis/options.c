/* options.c — the analysis options' defaults (their ranges are checked in checks.c). */
#include "core/analysis/options.h"

#include <string.h>

void ism_analysis_options_default(ism_analysis_options *o)
{
    memset(o, 0, sizeof *o);
    o->curvature = true;
    o->accuracy = true;
    o->project = false;
    o->threads = 0;
    o->singular_rel = 1e-6;
    o->newton_steps = 4;
}
