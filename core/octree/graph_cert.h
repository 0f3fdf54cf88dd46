/* graph_cert.h — a proof that f = 0 is one graph inside an octree node: f strictly monotone
 * along one direction over the whole box (by interval gradients), so every line in that
 * direction meets the surface at most once there — no closed piece, fold or second sheet
 * hides in the node. Under an error bound this replaces the corner-gradient agreement of the
 * flatness test (plot_test.c), which sampled 8 corners and asked for 26°: on the torus the
 * corners near the tube's core disagree long after the surface in the node is a gentle
 * graph. */
#ifndef ISM_GRAPH_CERT_H
#define ISM_GRAPH_CERT_H

#include <stdbool.h>
#include <stdint.h>
#include "core/eval/interval_jet.h"

/* The branch bytes of a forced evaluation are on the stack: longer tapes are not certified
 * across a kink (the CSG presets' tapes are 10-60 instructions). */
#define ISM_GRAPH_MAX_TAPE 256

/* True when every line along one direction d meets f = 0 at most once in the box lo..hi;
 * false when that cannot be shown (or jet does not fit t). Shown by ∇f(box) · d > 0 (or < 0)
 * over the box, d first the midpoint of ∇f's enclosure, then the direction whose slopes
 * clear 0 the most (the point of the enclosure nearest 0, graph_cert.c shared_direction);
 * failing both, on the box's eight halves with one d (graph_on_halves): halves where f keeps
 * one sign drop out, the others' enclosures (each about half as wide) must clear 0 along d.
 * Where f has kinks in the box (min, max, abs whose both branches the box allows; up to 3),
 * ∇f is enclosed once for each combination of their branches: every enclosure must clear 0
 * along d, with one sign (a CSG crease of two branches each monotone along d: the cube's
 * edges, whose nodes once split until 4 E across, plot_test.c); at f's top min/max a piece
 * whose partner's value decides f's sign over the box (max with the other below 0) counts
 * alone, there and on the halves. Barth's sextic at E 0.0259 / 0.00389 (the sphere's max
 * and the spikes' walls beside it): 45,552 / 90,872 -> 24,344 / 72,696 triangles. Counts in
 * graph32's notes. *intervals counts the evaluations;
 * nkinks, when not NULL, receives the kink count of the first, free evaluation over the box
 * ((size_t)-1 when jet is NULL or does not fit t), so that a caller need not ask it again. */
bool ism_graph_certified(const ism_tape *t, ism_ivjet_ws *jet, const double lo[3],
                         const double hi[3], uint64_t *intervals, size_t *nkinks);

/* ism_graph_certified from the whole box's enclosures alone (no halves): ∇f there clearing 0
 * along one direction. For a caller whose polygons need more than one graph: plot_test.c's
 * graph_node_passes past GRAPH_HALVES_ERRORS (there: the horn cyclide's curved nodes, one
 * graph each, whose polygons left artefacts). */
bool ism_graph_certified_whole(const ism_tape *t, ism_ivjet_ws *jet, const double lo[3],
                               const double hi[3], uint64_t *intervals);

/* The same verdict for the smooth piece of f that force picks (t's length of enum ism_branch
 * bytes: the natural enclosure of that piece's ∇f over the box, interval_jet.h): its zero set
 * is one graph in the box, which is f's zero set there when the caller knows so (the other
 * operand of a top min/max kept from 0 over the box). The halves are taken of f itself, no
 * branch forced: under that knowledge the same zero set. */
bool ism_graph_certified_piece(const ism_tape *t, ism_ivjet_ws *jet, const double lo[3],
                               const double hi[3], const uint8_t *force, uint64_t *intervals);

/* The same verdict from an enclosure g of ∇f over a box already computed
 * (ism_eval_interval_grad): ∇f · d clears 0 over it for d the midpoint of g's gradient. */
bool ism_graph_from_enclosure(const ism_ivgrad *g);

#endif
