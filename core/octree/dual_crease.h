/* dual_crease.h — the dual mesher's (dual.h) crease: f = min(a, b) or max(a, b) with that
 * min/max its tape's only one (ism_tape_top_min_max_only), a and b smooth. A node whose
 * interval allows both branches is judged here: emptiness by each branch's own enclosure,
 * a vertex ON the crease a = b = 0 (minimum-norm Newton from the node's centre, kept only
 * inside the node), or one branch alone over the node, or split. The distance a measurement
 * takes near the crease respects the kink (|f| / |∇f| is not a distance across it). The
 * design and its figure are in dual_crease.c's top comment. */
#ifndef ISM_DUAL_CREASE_H
#define ISM_DUAL_CREASE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include "core/eval/interval_jet.h"
#include "core/expr/tape.h"
#include "core/octree/sampler.h"

/* What a node with a kink (both branches possible over its box) is. */
enum ism_crease_node {
    ISM_CREASE_SPLIT = 0, /* nothing decided: split (at depth.max: declines min_max) */
    ISM_CREASE_EMPTY,     /* f kept from 0 over the box by a branch's own enclosure */
    ISM_CREASE_SMOOTH,    /* no crease point found in the box, the corners on one branch
                             whose corner gradients agree: a plain leaf of that branch */
    ISM_CREASE_VERTEX,    /* a crease point in the box (vertex), each branch's corner
                             gradients agreeing: the leaf's vertex on the crease */
    ISM_CREASE_PAIR,      /* at depth.max, small, no crease point in or near the box, the
                             crossings on both branches, each branch's one piece (curves
                             of its own crossed edges, at most one per face): a vertex per
                             branch (ism_dual_crease_branch_faces) */
};

/* Node lo..hi with corners p[8] (bit 0 = x, 1 = y, 2 = z), f at them in f[8], judged as
 * above; cos_min: the one-sheet test's agreement (flat_normal); small: the node is judged
 * by the measurement alone (no agreement asked; with crossings on both branches and no
 * crease point in it, ism_dual_crease_near's point). force: a zeroed buffer of s's tape
 * length, the caller's per thread (its last entry is overwritten). The crease point of an
 * ISM_CREASE_VERTEX node is ism_dual_crease_vertex's, else ism_dual_crease_near's: a
 * function of the box alone, which the caller finds again the same way. last: the node is
 * at depth.max (ISM_CREASE_PAIR only there: where splitting would decline). */
enum ism_crease_node ism_dual_crease_node(ism_sampler *s, ism_ivjet_ws *jet, uint8_t *force,
                                          const double (*p)[3], const double f[8],
                                          double cos_min, bool small, bool last);

/* The branch (0: a, 1: b) whose zero is f's root on the edge p0 -> p1 (p0 the lower end; the
 * branches' values bv0, bv1 at its ends, f changing sign along it): the branch changing sign
 * along it whose secant root has the other branch letting it be active there (max: the
 * other <= 0; min: >= 0); -1 when neither or both. A function of the edge alone: every node
 * round it labels it so. */
int ism_dual_edge_branch(ism_sampler *s, const double p0[3], const double p1[3],
                         const double bv0[2], const double bv1[2]);

/* The node's crossed edges (corners p[8], f[8]) labelled by ism_dual_edge_branch: -1 when one
 * cannot be labelled or a face holds more than two of one branch (two curves of it); 2 when
 * each branch has three or more (a piece of each apart: a pair leaf may hold them), else 1
 * (a face may hold two of each: a ridge along its diagonal, crossed four times). */
int ism_dual_crease_branch_faces(ism_sampler *s, const double (*p)[3], const double f[8]);

/* Branch k's vertex of a pair leaf (corners p[8], f[8]; ISM_CREASE_PAIR) into x: the mean of
 * branch k's secant roots on the crossed edges labelled k (ism_dual_edge_branch), moved onto
 * k = 0 by Newton along ∇k. */
void ism_dual_pair_vertex(ism_sampler *s, const double (*p)[3], const double f[8], int k,
                          double x[3]);

/* The crease point Newton reaches from the box's centre into x; false when Newton fails or
 * it lies farther than half the box's size outside the box along an axis. */
bool ism_dual_crease_near(ism_sampler *s, const double lo[3], const double hi[3], double x[3]);

/* The crease point of node lo..hi (minimum-norm Newton on a = b = 0 from its centre, else
 * from its corners in order) into x; false when every start fails or lands outside the
 * closed box. */
bool ism_dual_crease_vertex(ism_sampler *s, const double lo[3], const double hi[3],
                            double x[3]);

/* f kept from 0 over box lo..hi by the mean-value form from its 8 corners (values f[8],
 * ∇f enclosed in g over the box): 1 when f > 0 there, -1 when f < 0, 0 when not shown.
 * Also 1 when f >= 0 there from a corner where f is exactly 0 (the mesh's f = 0 counts as
 * outside: the node holds no f < 0, the sheet only touches its corner — Barth's sextic
 * through a lattice point). */
int ism_dual_mean_value_sign(const double f[8], const ism_ivgrad *g, const double lo[3],
                             const double hi[3]);

/* The distance from p to f = 0 as the dual mesh's measurements take it, given plain = |f| /
 * |∇f| at p (ism_sample_dist): plain itself when s's tape does not end in min/max or p is
 * far from the switch surface a = b; else the least of |p − x| + |f(x)| / |∇f(x)| over the
 * feet x of Newton along a, along b and onto the crease (each an upper bound of the distance
 * to first order at x: f = 0 is reached through x). e: the bound (Newton stops once a step
 * is below 1e-3 e: the residual is counted). */
double ism_dual_kink_dist_near(ism_sampler *s, const double p[3], double plain, double e);
/* ... for the n points p[0..n) with their plain[0..n), into out[0..n), the first test
 * inline and made once: every measured midpoint and centroid asks (sphere at E 7.14e-3,
 * 3,204 calls of ~32 instructions each out of line), the measure's tasks a batch at a time
 * (dual_measure.c pair_task). */
static inline void ism_dual_kink_dists(ism_sampler *s, const double (*p)[3],
                                       const double *plain, double e, double *out, size_t n)
{
    if (!ism_tape_top_minmax(s->tape)) { /* no switch surface (as switch_near answers) */
        memmove(out, plain, n * sizeof *out);
        return;
    }
    for (size_t j = 0; j < n; j++)
        out[j] = ism_dual_kink_dist_near(s, p[j], plain[j], e);
}

/* ... for one point: the batch's test and loop, so the two cannot part. */
static inline double ism_dual_kink_dist(ism_sampler *s, const double p[3], double plain,
                                        double e)
{
    double out;
    ism_dual_kink_dists(s, (const double (*)[3])p, &plain, e, &out, 1);
    return out;
}

/* Does a triangle with normal nrm (any length) and centroid c face along the gradient of
 * either branch (cosine above cos_min), the switch surface a = b within reach of c to first
 * order? False when s's tape does not end in min/max. A triangle beside the crease (a thin
 * one between crease vertices of neighbouring leaves) may face anywhere between the two
 * branches' normals, and the one active at its centroid need not be the one it lies on. */
bool ism_dual_kink_faces(ism_sampler *s, const double c[3], const double nrm[3], double reach,
                         double cos_min);


/* ism_dual_kink_dist at p from ism_plain_dist. */
double ism_dual_dist(ism_sampler *s, const double p[3], double e);

/* Crease vertices that two leaves found at one point (the crease on their common face: the
 * lens's x = 0 in a box centred on 0), for the n vertices ids[0..n) at pos[3 id ..]: to[k]
 * the least id of those within tol of ids[k] along every axis (joined transitively), ids[k]
 * itself when none. False when out of memory (to unset). */
bool ism_dual_weld(const double *pos, const uint32_t *ids, size_t n, double tol,
                   uint32_t *to);

/* Where the triangles tri[0..3 nt) (over vertices < nv) are not a manifold: the ends of
 * every mesh edge more than two triangles share, and every vertex whose triangles make more
 * than one fan (their edges opposite it are not one cycle: two cones meeting at a point),
 * into bad (room for 6 nt entries; an edge's two ends, a vertex once), their number
 * returned; (size_t)-1 when out of memory. The dual mesh is closed and manifold where
 * every leaf holds one sheet; beside a crease two crease pieces a cell apart can meet in
 * one small leaf. */
size_t ism_dual_not_manifold(const uint32_t *tri, size_t nt, size_t nv, uint32_t *bad);

#endif
