/* find.c — the singular-locus driver (find.h): search, then each stage on what the previous
 * ones left in out->boxes. */
#include "core/singular/find.h"
#include "core/singular/points.h"
#include "core/singular/search.h"

bool ism_locus_find(const ism_tape *f, const ism_locus_options *o, ism_locus *out,
                    ism_error *err)
{
    if (!ism_sing_search(f, o, out, err))
        return false;
    if (!ism_sing_points(f, o, out, err))
        return false;
    /* Next stages (the lead adds them here), each on the boxes not flagged ISM_LBOX_USED:
     *   curves.c  rank-2 boxes -> traced double curves and whiskers, ends typed
     *   sheets.c  rank-1 boxes -> double sheets
     * A stage cut short by the deadline or cancel sets out->incomplete itself. */
    return true;
}
