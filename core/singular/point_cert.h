/* point_cert.h — the certificate of one singular point, chosen by its Hessian's rank:
 * Krawczyk on ∇f (rank 3: nodes, isolated points), the deflated system (rank 2 with a
 * cubic term: cusps, deflate.h), the defining systems (rank 2 without: A3; rank 1: pinch
 * points; rank 0: triple points — typecert.h), else the reason none can hold. */
#ifndef ISM_SING_POINT_CERT_H
#define ISM_SING_POINT_CERT_H

#include <stdbool.h>
#include <stdint.h>
#include "core/eval/interval_jet.h"
#include "core/expr/expr.h"
#include "core/singular/locus.h"

/* Largest half-width of a certificate box, × the search box diagonal (the bound:
 * an enclosure of width <= 1e-9 × diagonal). */
#define ISM_SING_CERT_REL 0.5e-9

typedef struct ism_jet4_ws ism_jet4_ws;

/* The workspaces (the partial-derivative tapes are built at first use). */
typedef struct ism_pcert {
    const ism_tape *t;
    ism_ivjet_ws *jw;
    ism_jet4_ws *j3;    /* f's jets to order 3 (deflation, a contact's existence proof) */
    ism_jet4_ws *j4;    /* ... and to order 4 (the defining systems) */
    double diag;        /* the search box's diagonal */
    double hscale;      /* its Hessian scale (locus.h; 0 = unknown) */
    uint64_t *evals;    /* jet evaluations are added here */
    bool oom;
} ism_pcert;

/* False when out of memory. */
bool ism_pcert_init(ism_pcert *c, const ism_tape *t, double diag, double hscale,
                    uint64_t *evals);
void ism_pcert_free(ism_pcert *c);

/* Certifies pt (pt->p near the point; rank and null_vec, the eigenvector of H's smallest
 * |eigenvalue|, from H at pt->p) in a box of half-width ≤ ISM_SING_CERT_REL × diag: sets
 * certified, certificate, radius, perturbation, or uncertified_why (and, for a contact,
 * exists_radius when Poincaré–Miranda proves a zero of ∇f nearby). A defining system may
 * move pt->p by up to reach (its Gauss–Newton). *fbox: f over the certified box. Returns
 * pt->certified. */
bool ism_pcert_point(ism_pcert *c, ism_sing_point *pt, int rank, const double null_vec[3],
                     double reach, ism_interval *fbox);

/* The points the curve stage added (pinch, triple and degenerate points where curves meet:
 * uncertified, no reason yet) are certified by their Hessian's rank as above, moved to the
 * certified centre (≤ a tenth of a finest cell) with their residuals and eigenvalues
 * measured there, or given the reason. Stops at o's deadline or cancel (the rest keep no
 * reason; out->incomplete is set). False only when out of memory. */
bool ism_sing_certify_curve_points(const ism_tape *f, const ism_locus_options *o,
                                   ism_locus *out, ism_error *err);

#endif
