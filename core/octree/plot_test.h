/* plot_test.h — the flatness test that decides whether an octree node becomes a plotting
 * node or is subdivided further (paper §2, after Bloomenthal): the gradients at the node's
 * corners must agree (divergence criterion), every edge must pass the sign-and-gradient
 * test without suspecting two roots, every face must be crossed at most once, and the
 * polygon through the edge roots must be planar and close to the surface. */
#ifndef ISM_PLOT_TEST_H
#define ISM_PLOT_TEST_H

#include <stdbool.h>
#include "core/octree/corners.h"
#include "core/eval/interval_jet.h"
#include "core/octree/sampler.h"

typedef struct ism_flatness {
    double gradient_test;  /* paper eq. (1) */
    double normal_cos;     /* minimum cos between any two corner gradients */
    double plane_frac;     /* max distance from the plane / of the surface, × node size */
    double abs_tol;        /* and never more than this (world units): the maximum depth's
                              resolution, so a deeper request gives a finer mesh */
    double double_root_eps;/* the edge roots' double-root search (edge_roots.h), used under */
    int double_root_iters; /* max_error on small nodes whose edge gradients disagree */
    double max_error;      /* > 0: instead of the plane and centroid tests, the triangles the
                              node would emit must lie within this distance of the surface,
                              measured at their centroids and edge midpoints (cell_error.h);
                              0: the paper's tests above */
    double straddle_shift; /* > 0: the node's polygons are measured with their vertices
                              moved as straddle.h moves them, by this much */
    double box[6];         /* the request's box (straddle.h keeps its faces' vertices) */
} ism_flatness;

/* The flatness test's tolerance for a node `size` across: plane_frac × size, at most
 * abs_tol (how far its edge roots may lie off their plane, and their centroid off f = 0). */
double ism_flat_tolerance(double plane_frac, double abs_tol, double size);

/* lo, hi: the node's world box; k: its corner values. True when the node may be plotted
 * at this size. jet (interval gradients; NULL for none): under max_error a node whose
 * corner gradients disagree is still plotted when f is proven one graph in it
 * (graph_cert.h) and its roots and measured error pass.
 * blind (NULL for none): set when the node would pass without looking: under max_error, a
 * node small enough to be judged by its measured polygons alone (its corner gradients
 * unread) whose corners all share a sign has no polygon to measure — yet its corner
 * gradients disagree, as round a thin tube inside it, where without a bound the test fails.
 * The octree searches such a leaf for a hidden piece (octree_build.c). False whenever the
 * test returns false. */
bool ism_plot_test(ism_sampler *s, ism_ivjet_ws *jet, const ism_flatness *fl,
                   const double lo[3], const double hi[3], const ism_corners *k, bool *blind);

#endif
