/* thin_search.h — the search for a piece of f = 0 that a node's corners cannot see: a tube
 * thinner than the node passing between its lattice lines, a small closed sheet inside it,
 * a nappe piercing one of its faces in an island that crosses no edge, a ribbon of f of the
 * other sign lying in a face. The node's eight corners have one sign s; the search looks for
 * a point of the closed node where f has the other sign (a piece of the surface then
 * separates it from the corners), by Newton probes aimed past f = 0 and by interval
 * subdivision that proves s·f > 0 on the boxes it drops. */
#ifndef ISM_THIN_SEARCH_H
#define ISM_THIN_SEARCH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/eval/interval_jet.h"
#include "core/octree/sampler.h"

enum ism_thin_verdict {
    ISM_THIN_EXCLUDED,  /* intervals prove s·f > 0 on the whole node: nothing is hidden */
    ISM_THIN_FOUND,     /* a point of the node where s·f < 0: a hidden piece */
    ISM_THIN_UNDECIDED, /* neither within the search's levels and budget (f touching 0
                           without a sign change, as a double sheet f = g² does) */
    ISM_THIN_FOUND_KINKED, /* as FOUND, in a box where f has a min/max/abs kink (a CSG
                              crease): the point may be on a sliver of the solid's wedge
                              poking past the corners, found at every depth, which the box's
                              edges see; the caller tells it from a piece of its own
                              (octree_build.c) */
    ISM_THIN_KINKED,    /* not returned by the searches: the caller's verdict on a piece
                           found at a kink that the box's edges see (octree_build.c) */
};

/* One thread's scratch for the search (serves the tape it was made for and every tape
 * shortened from it). */
typedef struct ism_thin_ws {
    ism_ivjet_ws *jet;
    uint64_t n_boxes;   /* boxes examined, over every search with this workspace */
} ism_thin_ws;

/* The live preview's search (ism_poly_options.thin_coarse): Newton probes only, from the
 * box's centre and the centres of its eight octants (four quadrants in a face) — an octant
 * only where one batched interval over the eight leaves the other sign possible (a probe
 * stays in its box) — no interval proof. ISM_THIN_FOUND as ism_thin_search; otherwise
 * ISM_THIN_UNDECIDED (nothing found, nothing proven). A ball or a tube a fifth of the box
 * across is reached from the nearest of those centres (each step lands past f = 0); a piece
 * the probes miss is missing from the preview only. ISM_THIN_FOUND_KINKED instead of FOUND
 * when s->tape (shortened to the node) still holds a min or max: a CSG crease may cross the
 * box, whose slivers past the corners the probes find at every level (the gyroid ball at
 * depth 4: 132 "pieces", +22% triangles, when each counted); the caller keeps only what the
 * box's edges do not see. */
enum ism_thin_verdict ism_thin_probe(ism_sampler *s, const double lo[3], const double hi[3],
                                     int sign, double found[3]);

/* One of ism_thin_probe's Newton probes, from the centre of the box lo..hi (corners of sign
 * `sign`): true when it reached the other sign, at found. ism_thin_probe (its probes side by
 * side where f has a min or max) answers as these one by one would, in its order (the box's,
 * then its octants' in index order), the first to hit. */
bool ism_thin_probe_one(ism_sampler *s, const double lo[3], const double hi[3], int sign,
                        double found[3]);

bool ism_thin_ws_init(ism_thin_ws *w, const ism_tape *t);
void ism_thin_ws_free(ism_thin_ws *w);

/* Searches the closed box lo..hi, whose corners all have sign `sign` (±1), with s->tape
 * (valid inside the box). A box flat along an axis (lo == hi there: a node's face) is
 * searched in its plane. On ISM_THIN_FOUND, found (when not NULL) holds the point. The
 * cost is bounded (a fixed number of boxes and Newton steps), so UNDECIDED is possible. */
enum ism_thin_verdict ism_thin_search(ism_sampler *s, ism_thin_ws *w, const double lo[3],
                                      const double hi[3], int sign, double found[3]);

#endif
