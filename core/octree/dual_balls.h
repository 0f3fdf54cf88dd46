/* dual_balls.h — the dual mesh (dual.h) round isolated singular points: certified nodes
 * (cone apices, ∇f = 0 with an indefinite Hessian) and isolated points (definite Hessian).
 * The dual mesher's proofs cannot hold where ∇f vanishes, so round each point p a hole is
 * left (leaves meeting the ball of radius r0 place no vertex), the mesh round it is clipped
 * by the sphere |x − p| = r1 beyond the hole's rim, and every rim loop on that sphere (one
 * per nappe) is fanned to one vertex at p: the node becomes one mesh vertex shared by its
 * cones, as the primal path's conformance makes it (core/singular/conform.h). An isolated
 * point has no surface round it: no loop, no vertex (the primal path puts none either).
 *
 *            certified leaves (proofs hold)
 *        \  .  .  .  .  .  .  .  .  .  /     r0: the hole; leaves meeting it are no
 *         \ .  .  .______.  .  .  .  ./          larger than r0 / HOLE_LEAVES and hold
 *          \. . ./ hole   \. .  .  . /           no vertex (no proof needed there)
 *     nappe \  . | r0 . p  | .  .  . / nappe r1: the clip; every vertex of a triangle
 *            \___|____*____|________/            with an edge on the hole's rim lies
 *           rim loop  |  (fan to p)              inside it; triangles inside are
 *           on the    |                          dropped, those across are cut on the
 *           sphere r1 |                          sphere, the cut points moved onto f = 0
 *
 * The fan's triangles (and the cut ones) are measured like the dual mesh's own: centroid
 * and edge midpoints within E of f = 0. A ruling from the apex lies on a quadratic cone
 * exactly and within O(r² |f'''| / |H|) of a node's surface, so where a fan misses E the
 * ball shrinks (ISM_DUAL_BALL_SHRINK) and the dual mesh is made again. */
#ifndef ISM_DUAL_BALLS_H
#define ISM_DUAL_BALLS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/mesh/mesh.h"
#include "core/octree/sampler.h"

typedef struct ism_dual_ball {
    double p[3];  /* the certified point */
    double r0;    /* the hole: leaves meeting the ball place no vertex */
    double leaf;  /* a node meeting the hole is split while larger than this */
    double limit; /* the clip sphere's radius stays below this (balls apart, in the box) */
    int nappes;   /* rim loops the clip must cut: 2 round a node, 0 round an isolated point */
} ism_dual_ball;

/* The balls filed by where they reach: a uniform grid over their limits, each cell listing (in
 * ascending order) the balls whose limit ball meets the cell's box (by bounding boxes), so a
 * box inside one cell asks only those; a box across cells, or no grid, asks every ball.
 * Answers are those of asking every ball in order, bit for bit. */
typedef struct ism_dual_ball_cover {
    double lo[3], cell; /* the grid's origin and cell side; cell 0: no grid */
    double inv;         /* 1 / cell */
    int32_t dim[3];
    uint32_t *start;    /* per cell (x fastest): its first entry in idx; one more at the end */
    uint32_t *idx;
} ism_dual_ball_cover;

/* Files the n balls b (limits made) over the box their limits span (grown by a limit: a
 * box off it meets none); a cover without a grid (every ball asked) when there are none or
 * memory runs out. */
void ism_dual_ball_cover_init(ism_dual_ball_cover *c, const ism_dual_ball *b, size_t n);
void ism_dual_ball_cover_free(ism_dual_ball_cover *c);

/* How many times a ball may halve before the dual mesher declines (point_fan). */
#define ISM_DUAL_BALL_SHRINKS 5

/* The ball round point pt (x, y, z, clearance, nappes: poly_options.dual_points) in box
 * under the bound E, halved `shrink` times: r0 a share of the clearance, of the distance to
 * the box and of what E allows the fan. */
void ism_dual_ball_make(ism_dual_ball *b, const double pt[5], const double box[6],
                        double max_error, int shrink);

/* What a node lo..hi of side `size` is next to the balls (cv: their cover, or NULL): -1
 * meets none (the dual mesher's own tests), 0 meets a hole and is larger than its leaf
 * (split), 1 a hole leaf (no vertex; also at the last level, at_max). */
int ism_dual_balls_node(const ism_dual_ball *b, size_t n, const ism_dual_ball_cover *cv,
                        const double lo[3], const double hi[3], double size, bool at_max);

/* Does the box lo..hi, of side `size` (0: any), meet the ball of radius `limit` round one of
 * the points whose hole leaves are no smaller? (cv: the balls' cover, or NULL.) */
bool ism_dual_balls_near(const ism_dual_ball *b, size_t n, const ism_dual_ball_cover *cv,
                         const double lo[3], const double hi[3], double size);

enum ism_fan_status {
    ISM_FAN_OK = 0,
    ISM_FAN_MISS,   /* a fan or cut triangle beyond E round ball *which: shrink it */
    ISM_FAN_BAD,    /* a node's sphere did not cut two loops, a rim beyond the limit, a
                       triangle across the sphere with no vertex inside, or the mesh not
                       closed after the fans */
    ISM_FAN_NO_MEMORY,
};

/* The centroid of triangle p[0..3) within e of f = 0 (|f| / |∇f| there) and the triangle's
 * normal not turned over against ∇f there: the centroid half of the measure the dual mesh's
 * triangles (dual_measure.c) and the fans (ism_dual_balls_fan) meet. */
bool ism_dual_centroid_within(ism_sampler *s, const double *p[3], double e);

/* The centroid of p[0..3), as ism_dual_centroid_within takes it, into c. */
void ism_dual_centroid(const double *p[3], double c[3]);

/* ism_dual_centroid_within with f and ∇f at the centroid c (ism_dual_centroid) and its
 * ism_plain_dist there (plain) given: the same answer, for callers that take the
 * centroids' gradients in batches (ism_plain_dists). */
bool ism_dual_centroid_within_at(ism_sampler *s, const double *p[3], const double c[3],
                                 double f, const double g[3], double plain, double e);

/* Triangle v[0..3) of m meets E as the dual mesh's own do (dual_measure.c): its centroid
 * (ism_dual_centroid_within) and edge midpoints within e of f = 0, its normal along ∇f at
 * the centroid. The fans and cuts round the balls and the box's cuts (dual_box.h) are
 * measured so. */
bool ism_dual_triangle_within(ism_sampler *s, const ism_mesh *m, const uint32_t *v, double e);

/* Clips the closed-but-for-the-holes mesh m round each ball and fans its rim loops to the
 * ball's point (one vertex per node; nothing for an isolated point); measures the new
 * triangles against E with s. On anything but OK, m is left in an unspecified state (the
 * caller makes the mesh again or gives up). shrink[0..n): 1 for every ball a MISS or BAD
 * is about, to be halved; a BAD with none marked cannot be helped by the balls. rim[0..n):
 * each ball's clip sphere as far as the clip got (0: none). cv: the cover of b[0..n) (the
 * caller's, ism_dual_ball_cover_init; one without a grid asks every ball). */
enum ism_fan_status ism_dual_balls_fan(ism_mesh *m, ism_sampler *s, const ism_dual_ball *b,
                                       size_t n, const ism_dual_ball_cover *cv,
                                       double max_error, uint8_t *shrink, double *rim);

#endif
