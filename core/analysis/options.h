/* options.h — the defaults of ism_analysis_options (options.c); public (analysis.h includes
 * it). */
#ifndef ISM_AN_OPTIONS_H
#define ISM_AN_OPTIONS_H

#include "core/analysis/analysis_types.h"

/* Fills o with the defaults documented in ism_analysis_options. */
void ism_analysis_options_default(ism_analysis_options *o);

#endif
