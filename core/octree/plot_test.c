/* plot_test.c — flatness of an octree node: corner gradient divergence, the sign-and-gradient
 * edge test, at most one crossing curve per face, then either planarity of the edge roots
 * and the distance of their centroid to the surface (the paper), or, under an error bound,
 * the distance of the node's would-be triangles to the surface (cell_error.h); at a CSG
 * crease, each branch's corner gradients, or the one branch whose zero set is f's proven one
 * graph (one_branch_graph). */
#include "core/octree/plot_test.h"
#include "core/eval/eval.h"
#include "core/eval/interval_ops.h"
#include "core/eval/top_branch.h"
#include "core/expr/expr.h"
#include "core/expr/tape.h"
#include "core/octree/cell_cache.h"
#include "core/octree/cell_error.h"
#include "core/octree/crease_split.h"
#include "core/octree/edge_roots.h"
#include "core/octree/graph_cert.h"

#include <assert.h>
#include <math.h>
#include <string.h>

/* Under an error bound, a node at most this many times the bound across is judged by its
 * measured error alone: its corner gradients may disagree, an edge may hold two roots and
 * a face may be crossed by two curves. Near a crease (where a max() joins two surfaces)
 * all three hold at every level — the solid's wedge pokes through edges and faces — and
 * the node would otherwise be refined to depth.max whatever the bound. The polygoniser
 * finds both roots of such an edge and pairs a face's four crossings (face_lines.c); what
 * the leaf really emits is measured after polygonising, and a leaf that missed the bound
 * is split in the next round (refine.h). Whatever a node this small could hide is about as
 * small as the bound — but a tube thinner than E is still the surface's topology (a horn down
 * to its point): a node with no polygon is probed for one (ism_plot_test's blind). Gyroid
 * ball at E = 0.0334 (box ±1.5, depth 10): 101,900 -> 19,526 triangles, max centroid distance
 * 0.0303 both, χ −18 both.
 *
 * Near a crease that "as small as the bound" is not sampled but proven (crossing_graphs): a
 * node that emits polygons through one of these allowances while its tape keeps a kink over
 * the box (f = max(a, b) or min with both branches possible there: the two surfaces a = 0 and
 * b = 0 cross in it) must show ∇a and ∇b, each an interval enclosure over the whole box with
 * its branch forced, clearing 0 along one direction d (ism_graph_certified across the kink).
 * Then along every line parallel to d, f is continuous and piecewise smooth with slopes of one
 * sign, so it meets f = 0 at most once: inside the box the zero set is one sheet, a graph over
 * the plane across d, with the crease a curve on it — no closed piece, second sheet or tube
 * the corners could hide, whatever their gradients (which mix the branches) say. Any crease
 * whose normals meet at less than 180° less the enclosures' spread passes (the cube minus a
 * ball's 140°). What the node's polygons then miss is geometry within the node, measured after
 * polygonising like any node's (cell_error.h, refine.h). A node it cannot certify is split.
 * Counted on all 43 presets in their own boxes at the default bound (1e-3 × the diagonal):
 * no node with a kink was refused (certified: gyroid-ball 6, schwarz-d 1,806, three-balls
 * 322, steinmetz 216 nodes), so no mesh changes. Nodes with no kink keep the sampled rule:
 * there the allowances serve singular structure — two sheets crossing on a double curve are
 * no graph; the singular stage finds points and curves with its own certificates and
 * conformance meshes round them — and the interval test fails on many (not certified:
 * steiner-roman 1,812 of 5,904, crossing-spheres 7,528 of 9,776, klein-bottle 1,596 of
 * 3,892, horn-cyclide 1,136 of 1,656, heart 584 of 1,856, cross-cap 76 of 772; most several
 * nodes from the locus: the enclosure of a quartic's gradient over a node is wide), so
 * requiring it there would split them to depth.max. The nodes such a box's smallest side
 * makes "small" are also judged so (min_side: double-torus's flat box makes nodes 0.091 ×
 * 0.056 × 0.025 at E 0.007; none of them emits a polygon through an allowance). Cost
 * (callgrind, raw mesh, one thread, ism_polygonise): schwarz-d 2,231.6M -> 2,233.6M,
 * crossing-spheres 1,385.5M -> 1,389.2M, steinmetz at E = 3e-3 (5,117 certificates, the
 * most seen) 414.7M -> 427.3M; mesh_identity.py 217 of 217 identical. */
#define CREASE_CELL_ERRORS 4.0

/* Where f's crease is read off its smooth pieces (crease_split.h's pieces mode) a node whose
 * corners lie on two pieces is judged by its polygons cut along the crease (crease_cell) up to
 * this many bounds across its smallest side (min_side: in a flat or irregular box the long
 * sides may be several times that, as for CREASE_CELL_ERRORS), and one whose corners show three
 * or more pieces (a junction: a cube's corner) up to CREASE_JUNCTION_ERRORS, when every piece
 * is a plane over the node (PLANE_PIECE_COS) or the pieces meet at most a right angle apart
 * (CURVED_CREASE_COS); past them the corner test decides, as for any node. Without these the
 * only crease-aware judgement was that of f's top min/max, and the cube, max(|x|, |y|, |z|) −
 * 1, has none: every crease node went to the corner test, whose uncut polygons across a 90°
 * crease miss E until depth 7 (152 / 296 / 584 nodes refused at depths 4 / 5 / 6, crease25),
 * and the quality pass then cost 1.29–1.33 times the polygonisation (callgrind). Measured,
 * cube, --quality good, default bound (E 4.5e-3), the five cusp22 boxes own / 1e-3 / irr / c037
 * / 1e-4: with no limit the raw mesh is 768 triangles, exact, but the pass loses corner
 * vertices and leaves 8.7–8.9° triangles there (its junction fans too coarse); both limits 24 E
 * (nodes of 18 E, depth 5 of the ±1.3 box): 2,064 raw, 20.4–21.5°, pass / polygonise 0.94 /
 * 0.97 / 1.10 / 1.06 / 0.96 (env hooks); two pieces 40 E (36 E, depth 4), junctions 24 E: 1,248
 * raw, 16.8 / 18.9 / 12.4 / 17.1 / 16.8° (main: 18.1 / 14.5 / 10.1 / 12.9 / 17.9°), pass /
 * polygonise 0.90 / 0.92 / 0.86 / 0.87 / 0.91 (main 1.29 own, 1.30 irr, 1.33 c037; the whole
 * run 499M -> 67M own); 80 E for two pieces: 7.3–10.0°. */
#define CREASE_PIECES_ERRORS 40.0
#define CREASE_JUNCTION_ERRORS 24.0

/* The pieces' judgement of a node (CREASE_PIECES_ERRORS) where each piece's corner gradients
 * are one direction up to rounding: planes over the node (the cube's faces), whatever angle
 * they meet at; curved pieces only as open creases (CURVED_CREASE_COS). 1e-12 is an angle of
 * 1.4e-6 rad: far above the rounding of a normalised dot product (~1e-16, an exact plane's
 * corner gradients in a shifted box agree to that), far below the turn of the least curved
 * piece (a node of 40 E on a ball of radius R turns its normals by about 40 E / R: 0.2 rad
 * for E = 5e-3, R = 1). */
#define PLANE_PIECE_COS (1 - 1e-12)

/* Curved pieces are judged so where they meet at most a right angle apart: at every corner
 * each other piece of the node's gradient (ism_eval_piece_gradient, the piece continued past
 * its region) within 90° of the corner's own. Sharper creases of curved pieces in coarse
 * cells leave the quality pass needles where three meet (the pass's junction crowd, stein26):
 * --quality good, default bound, the five cusp22 boxes own / 1e-3 / irr / c037 / 1e-4, with
 * curved pieces admitted at any angle: three-balls (balls of r² 0.5 meeting 95° apart) 20.3
 * / 0.83 / 18.4 / 1.51 / 1.21°, and the same balls negated (max of −ball: convex creases,
 * the same point set) 10.8 / 0.83 / 20.9 / 20.3 / 1.04°, while r² 0.6 (84° apart) gave 20.7 /
 * 20.1 / 13.4 / 5.33 / 21.0° (5.33 is main's c037 figure too) and r² 0.8 (71°) 20.1 / 20.1 /
 * 17.5 / 19.3 / 20.0° (main 10.3–14.4°). Convexity does not separate them; the angle does.
 * Steinmetz's cylinders meet at most 60° apart (x² at the crease y = ±z): 9,024 -> 2,040 raw
 * triangles, 20.4 / 20.1 / 15.1 / 11.2 / 20.7° (main 19.3 / 12.5 / 11.7 / 13.3 / 19.1°). The
 * cube's planes meet at exactly 90° and are PLANE_PIECE_COS's, with no such need. */
#define CURVED_CREASE_COS 0.0

/* graph_node_passes proves its node one graph on the node's halves (ism_graph_certified) up
 * to this many bounds across its smallest side, bigger nodes by the whole box's enclosures
 * alone (ism_graph_certified_whole). The halves prove curved nodes many E across: the horn
 * cyclide at E 0.064 (depth 3:8, own box) with the halves up to 32 E passed nodes 2 across,
 * each one graph (sampled along its d: no line met it twice), whose polygons the tests after
 * the proof do not follow (4 + 4 non-manifold artefacts); up to 16 E none. bench_error, one
 * thread, callgrind ism_mesh_surface, whole enclosures only -> halves up to 16 E: Klein 0.0141
 * 541.8M -> 492.9M instructions, 17,546 -> 16,704 triangles, max_c 0.0100, max_m 0.0140778
 * both; Barth 0.00389 1,721.1M -> 1,716.8M, 72,696 -> 70,632, max_c 0.00317, max_m 0.00388
 * both; Barth 0.0259 24,344 both (its nodes pass elsewhere). Guarded by
 * thin::horn_cyclide_under_a_bound (own box, E 0.064: 32 leaves 4 + 4 artefacts there, quick
 * runs included). The crease sites (one_branch_graph, crossing_graphs) take the halves at every
 * size: Barth E 0.1 / 0.05 / 0.0259 / 0.01 / 0.00389 and the gyroid ball 0.05 to 0.00109, depth
 * 10, three placements, have the fine reference's topology (χ −28 / −18, one piece, no boundary
 * or non-manifold edge, no artefact) with them, without them, or with either site's proof
 * replaced by true (mendA32's notes). */
#define GRAPH_HALVES_ERRORS 16.0

/* The screen of graph_node_passes: a polygon's triangles err less than the sag at its
 * centroid (a quad's diagonal midpoint is its centroid; a fan's triangles lie between the
 * centre on f = 0 and the sides), so a node whose roots' centroid lies several bounds off
 * the surface cannot meet E; 4 leaves room for the secant roots' own error. */
#define CENTROID_SAG_ERRORS 4.0

static bool normals_agree(const double (*n)[3], double normal_cos)
{
    for (int i = 0; i < 8; i++)
        for (int j = i + 1; j < 8; j++)
            if (ism_dot3(n[i], n[j]) < normal_cos)
                return false;
    return true;
}

/* The paper's double-root search along edge c0-c1 finds nothing. One interval over the
 * edge first: where it proves |f| > eps the search (up to double_root_iters gradients, a
 * third of the gyroid's time under max_error) could find neither a sign change nor a
 * tangent point, so the answer is the same without it. */
static bool no_roots(ism_sampler *s, const ism_flatness *fl, const ism_corners *k, int c0,
                     int c1)
{
    if (!ism_segment_may_reach(s, k->p[c0], k->p[c1], fl->double_root_eps))
        return true;
    ism_root_params prm = {fl->gradient_test, fl->double_root_eps, fl->double_root_iters,
                           false}; /* the search alone: crease only gates it elsewhere */
    double t;
    return ism_double_root_search(s, &prm, k->p[c0], k->p[c1], k->f[c0], k->f[c1], &t) == 0;
}

static double min_side(const double lo[3], const double hi[3]);

/* The branch of f's top min/max at corner c (ism_crease_branch's label), through the
 * thread's memo when there is one (only asked while the node's tape keeps that min/max:
 * crease_cell). Its values are evaluated here, not through ism_crease_branch, to learn
 * whether f's own gradient at the corner, k->g[c], is that branch's gradient: where f's
 * gradient follows the label (ism_top_gradient_branch: the branch wins strictly, or it is
 * the second operand) the memo keeps k->g[c] as corner_gradient's
 * answer, bit for bit the one ism_crease_branch would evaluate (a tape keeping the min/max
 * gives f's branches' values and gradients bit for bit, octree.h; min/max pass the chosen
 * operand's partials on whole). Barth's sextic at E 0.0259: 14,137 branch gradients
 * (10.7M instructions) that crease_cell asked for at corners already labelled. */
static int corner_branch(ism_sampler *s, const ism_corners *k, int c)
{
    ism_label_entry *m = k->memo ? ism_label_slot(k->memo->labels, k->key[c]) : NULL;
    if (m && m->key == k->key[c])
        return m->label;
    /* Only the build asks (octree_build.c), whose samplers hold no local tape (only
     * polygonise.c's leaves set one): the label is on s->tape, which is ism_crease_branch's
     * choice there (top_tape), and every label this writes is the memo's. */
    assert(!s->local);
    double v[2];
    s->n_point++; /* as ism_crease_branch counts the label's values */
    if (!ism_eval_top_values(s->tape, s->ws, k->p[c][0], k->p[c][1], k->p[c][2], v))
        return -1;
    int b = ism_top_active_branch(s->tape, v);
    if (m && b >= 0) {
        bool own = ism_top_gradient_branch(s->tape, v) == b;
        *m = (ism_label_entry){k->key[c], b, own, {0, 0, 0}};
        if (own)
            memcpy(m->g, k->g[c], sizeof m->g);
    }
    return b;
}

/* The gradient of f's top min/max branch at corner c (ism_crease_branch's g), through the
 * thread's memo when the corner's label is there (corner_branch has just asked). A pure
 * function of the point as the label is: a tape keeping that min/max gives f's branches'
 * values and gradients bit for bit (octree.h). */
static void corner_gradient(ism_sampler *s, const ism_corners *k, int c, double g[3])
{
    ism_label_entry *m = k->memo ? ism_label_slot(k->memo->labels, k->key[c]) : NULL;
    if (m && m->key == k->key[c] && m->has_g) {
        memcpy(g, m->g, sizeof m->g);
        return;
    }
    if (ism_crease_branch(s, k->p[c], g) >= 0 && m && m->key == k->key[c]) {
        memcpy(m->g, g, sizeof m->g);
        m->has_g = 1;
    }
}

/* A crease node whose corners on one branch disagree (crease_cell) where f = 0 is one branch's
 * zero set alone: the other operand of f's top max is below 0 over the box (min: above), so
 * f = max(a, b) vanishes exactly where a does and has a's sign. That branch's zero set is
 * then proven one graph over the box by its own gradient's enclosure (graph_cert.h). Barth's
 * sextic B cut by the ball, max(B, r² − 2.25): on the spikes' walls toward the ball the
 * sphere's branch is active just off the sheet on its negative side, so the crease
 * B = r² − 2.25 hugs the sheet without meeting it there, and these nodes were split until
 * B's corner gradients agreed to 26°, whatever E: at E 0.1 / 1e-2 / 3e-3, 65,336 /
 * 79,776 / 111,200 triangles, with this 50,952 / 64,536 / 104,912 (χ −28, 30 nodes, max
 * centroid and midpoint distances unchanged; bench_error barth-sextic, depth.max 10). The
 * piece's Taylor form (dual_cert.h) would prove more but needs the piece's gradient at the
 * box's centre, which the forced interval jet gives only where the centre does not decide
 * the branch itself (interval_jet.h: a decided branch wins over the force). One graph is
 * not yet within E: a node this admits still goes to ism_cell_error_cut in crease_cell, and
 * where that cannot estimate, to the measurement after polygonising (a leaf missing E is
 * split in the next round), now also with corner normals apart past normal_cos. */
static bool one_branch_graph(ism_sampler *s, ism_ivjet_ws *jet, const ism_corners *k)
{
    const ism_tape *t = s->tape;
    const size_t len = ism_tape_length(t);
    if (len > ISM_GRAPH_MAX_TAPE)
        return false; /* the force bytes are on the stack */
    ism_interval v[2];
    int is_max = ism_eval_interval_top(t, s->ws, iv(k->p[0][0], k->p[7][0]),
                                       iv(k->p[0][1], k->p[7][1]), iv(k->p[0][2], k->p[7][2]),
                                       v);
    if (is_max < 0)
        return false;
    s->n_interval++;
    int live = is_max ? (v[1].hi < 0 ? 0 : v[0].hi < 0 ? 1 : -1)
                      : (v[1].lo > 0 ? 0 : v[0].lo > 0 ? 1 : -1);
    if (live < 0)
        return false;
    uint8_t force[ISM_GRAPH_MAX_TAPE];
    memset(force, ISM_BRANCH_FREE, len);
    force[len - 1] = live == 0 ? ISM_BRANCH_A : ISM_BRANCH_B;
    return ism_graph_certified_piece(t, jet, k->p[0], k->p[7], force, &s->n_interval);
}

/* The corners' labels by f's top min/max branch (corner_branch): true when the node's
 * corners lie on both branches. */
static bool branch_labels(ism_sampler *s, const ism_corners *k, ism_piece branch[8])
{
    int seen = 0;
    for (int c = 0; c < 8; c++) { /* labels first: most nodes lie on one branch */
        int b = corner_branch(s, k, c);
        if (b < 0)
            return false;
        branch[c] = (ism_piece)b;
        seen |= 1 << b;
    }
    return seen == 3;
}

/* The corners' unit normals n (f's gradients): false where one is no direction. */
static bool corner_normals(const ism_corners *k, double n[8][3])
{
    for (int c = 0; c < 8; c++) {
        memcpy(n[c], k->g[c], sizeof n[c]);
        double len = ism_normalise3(n[c]);
        if (!(len > 0) || !isfinite(len))
            return false;
    }
    return true;
}

/* How many directions, PLANE_PIECE_COS apart, the corners' unit normals n point in; 0 where
 * there are more than `most` (a curved sheet's eight corners point eight ways). */
static int few_directions(const double n[8][3], int most)
{
    int dir[8], ndir = 0;
    for (int c = 0; c < 8; c++) {
        int d = 0;
        while (d < ndir && !(ism_dot3(n[c], n[dir[d]]) >= PLANE_PIECE_COS))
            d++;
        if (d == ndir) {
            if (ndir == most)
                return 0;
            dir[ndir++] = c;
        }
    }
    return ndir;
}

/* Each piece's corner normals n one direction (PLANE_PIECE_COS): planes over the node. */
static bool plane_pieces(const double n[8][3], const ism_piece branch[8])
{
    for (int i = 0; i < 8; i++)
        for (int j = i + 1; j < 8; j++)
            if (branch[i] == branch[j] && !(ism_dot3(n[i], n[j]) >= PLANE_PIECE_COS))
                return false;
    return true;
}

/* Every corner's other pieces' normals within CURVED_CREASE_COS of its own normal n (each
 * piece's gradient asked once a corner). */
static bool open_creases(ism_sampler *s, const ism_corners *k, const double n[8][3],
                         const ism_piece branch[8])
{
    for (int j = 0; j < 8; j++)
        for (int i = 0; i < 8; i++) {
            bool asked = branch[i] == branch[j];
            for (int h = 0; h < i && !asked; h++)
                asked = branch[h] == branch[i];
            if (asked)
                continue;
            double g[3];
            s->n_point++;
            ism_eval_piece_gradient(s->tape, s->ws, branch[i], k->p[j][0], k->p[j][1],
                                    k->p[j][2], g);
            double len = ism_normalise3(g);
            if (!(len > 0) || !isfinite(len) || !(ism_dot3(g, n[j]) >= CURVED_CREASE_COS))
                return false;
        }
    return true;
}

/* A node's corners show at most this many smooth pieces where they are planes (few_
 * directions' screen): a cube's corner shows three faces. */
#define PLANE_PIECES_MOST 4

/* In pieces mode, the corners' labels by their smooth piece (ism_eval_piece, the labels
 * ism_crease_split cuts by), for a node within CREASE_PIECES_ERRORS (two pieces) or
 * CREASE_JUNCTION_ERRORS (more) whose pieces are planes or meet as open creases
 * (CURVED_CREASE_COS): how many pieces the corners show (2, or 3 for three or more), with
 * the corners' unit normals n (f's gradients, each its own piece's); 0 where the node is not
 * judged so. A node's tape with no kink left over it, or corners whose normals all point one
 * way, are not asked their pieces: one piece, or two planes with one normal meeting in no
 * crease over the node (flat nodes of a cube's face stop here). */
static int piece_labels(ism_sampler *s, const ism_flatness *fl, const double lo[3],
                        const double hi[3], const ism_corners *k, ism_piece branch[8],
                        double n[8][3])
{
    double size = min_side(lo, hi);
    if (!(size <= CREASE_PIECES_ERRORS * fl->max_error) || ism_tape_kinks(s->tape) == 0 ||
        !corner_normals(k, n))
        return 0;
    int dirs = few_directions(n, PLANE_PIECES_MOST);
    if (dirs == 1)
        return 0;
    ism_piece other = ISM_PIECE_NONE;
    int np = 1;
    for (int c = 0; c < 8; c++) {
        s->n_point++;
        branch[c] = ism_eval_piece(s->tape, s->ws, k->p[c][0], k->p[c][1], k->p[c][2]);
        if (branch[c] == ISM_PIECE_NONE)
            return 0;
        if (branch[c] != branch[0] && branch[c] != other) {
            np = other == ISM_PIECE_NONE ? 2 : 3;
            other = branch[c];
        }
    }
    if (np == 1 || (np == 3 && !(size <= CREASE_JUNCTION_ERRORS * fl->max_error)))
        return 0;
    if (dirs > 1 && plane_pieces(n, branch))
        return np;
    return open_creases(s, k, n, branch) ? np : 0;
}

/* Under an error bound, a node whose corners lie on both branches of f's top min/max (a
 * CSG crease may pass through it): f's own corner gradients mix the two branches' and never
 * agree, so the node is judged by each branch's gradients at its own corners instead, and
 * where f's crease is read off its smooth pieces (pieces mode), a node piece_labels labels
 * (planar pieces or open creases, CREASE_PIECES_ERRORS / CREASE_JUNCTION_ERRORS), by f's own corner
 * gradients, each that of its corner's piece; in both
 * its triangles, cut along the crease (crease_split.h), by what they measure after
 * polygonising (a leaf that misses E is split in the next round). -1: not such a node. The
 * gyroid ball at E = 3e-3 (box ±1.5, depth 7): 312,508 -> 45,482 triangles; at 1e-3, depth
 * 10: 586,994 -> 117,882, max centroid distance 2.3e-3 -> 1.18e-3. */
static int crease_cell(ism_sampler *s, ism_ivjet_ws *jet, const ism_flatness *fl,
                       const double lo[3], const double hi[3], const ism_corners *k,
                       bool critical)
{
    static const double any[2] = {0, 0};
    ism_piece branch[8];
    double n[8][3]; /* the corners' unit normals: in pieces mode piece_labels' */
    bool pieces = s->crease_pieces && piece_labels(s, fl, lo, hi, k, branch, n) > 0;
    if (!pieces && ism_top_active_branch(s->tape, any) < 0)
        return -1; /* the node's tape has no top min/max left: no label (crease_split.h) */
    if (!pieces && !branch_labels(s, k, branch))
        return -1;
    /* two corners of one branch whose normals part past normal_cos, or a corner where its
     * branch's gradient or f's (critical) vanishes (its normal is no direction: only the
     * certificate can vouch for the node). f's is asked apart: at a corner on the crease
     * (a == b) f's derivative takes b (eval_gradient.c) but the label a
     * (ism_top_active_branch), so ∇f = ∇b = 0 may sit beside a labelled ∇a that is not
     * (test_plot_test_tie.c). */
    bool disagree = critical;
    for (int c = 0; c < 8 && !pieces; c++) { /* pieces: every n[c] a direction already */
        corner_gradient(s, k, c, n[c]);
        double len = ism_normalise3(n[c]);
        disagree |= !(len > 0) || !isfinite(len);
    }
    for (int i = 0; i < 8 && !disagree; i++)
        for (int j = i + 1; j < 8 && !disagree; j++)
            disagree = branch[i] == branch[j] && ism_dot3(n[i], n[j]) < fl->normal_cos;
    if (disagree && !one_branch_graph(s, jet, k)) /* asked once: one box, one answer */
        return 0;
    double err;
    if (ism_cell_error_cut(s, k, fl->max_error, &err))
        return err <= fl->max_error;
    /* Polygons the estimate cannot follow (a face crossed at 1 or 4 points): the measurement
     * after polygonising decides, in pieces mode too (revC 6, measured: no node of the 42
     * presets' own boxes at the default bound, nor of cube-minus-ball and three-balls at 0.3 /
     * 1 / 3 / 10 × it in the own, irr and c037 boxes, gets here in pieces mode; a slab
     * |x − y − 0.003| − 0.01 in ±1 at the default bound sends 256 nodes here, all exact
     * (1,984 triangles; refused, 133,456); cut by a ball of r² 0.8, depth 3:8, E met in 2
     * error rounds with 15,030 triangles, refused 186,312, the same max distances). */
    return 1;
}

/* A node judged by its measure alone that used an allowance of CREASE_CELL_ERRORS is proven
 * one graph when its tape keeps a kink over the box (two crossing surfaces: ism_graph_
 * certified across it); true also where the tape keeps none (the sampled rule, see there).
 * The kinks are asked only of a node the certificate refuses. */
static bool crossing_graphs(ism_sampler *s, ism_ivjet_ws *jet, const double lo[3],
                            const double hi[3])
{
    size_t nk; /* the certificate's own free evaluation: (size_t)-1 without a jet */
    return ism_graph_certified(s->tape, jet, lo, hi, &s->n_interval, &nk) || nk == 0;
}

/* A node judged by its measure alone passes crossing_graphs when it used an allowance: an
 * edge or face (allowed) or corner normals n that disagree. Asked of a node about to pass,
 * cheapest first (a tape with no kinking instruction needs none of it). */
static bool crossing_ok(ism_sampler *s, ism_ivjet_ws *jet, const ism_flatness *fl,
                        const double lo[3], const double hi[3], const double (*n)[3],
                        bool allowed)
{
    if (!ism_tape_has_kink(s->tape) || (!allowed && normals_agree(n, fl->normal_cos)))
        return true;
    return crossing_graphs(s, jet, lo, hi);
}

/* No root on any of the n cube edges listed (no_roots on each). */
static bool edges_rootless(ism_sampler *s, const ism_flatness *fl, const ism_corners *k,
                           const int *edges, int n)
{
    for (int i = 0; i < n; i++) {
        int c0, c1, faces[2];
        ism_cube_edge(edges[i], &c0, &c1, faces);
        if (!no_roots(s, fl, k, c0, c1))
            return false;
    }
    return true;
}

/* A node whose corner gradients disagree, under an error bound: when crossed (nroots > 0),
 * its secant roots' centroid (their sum / nroots) within CENTROID_SAG_ERRORS (E + shift) of
 * the surface — a cheap screen before the exact roots (most such nodes are far too coarse) —
 * then f proven one graph over the box (on its halves up to GRAPH_HALVES_ERRORS, by the
 * whole box's enclosure past it), and no root on a same-sign edge whose gradients disagree (a
 * graph may dip through an edge twice; the polygon would miss it). The measurement decides
 * after. */
static bool graph_node_passes(ism_sampler *s, ism_ivjet_ws *jet, const ism_flatness *fl,
                              const double lo[3], const double hi[3], const ism_corners *k,
                              const double sum[3], int nroots, const int *disagree,
                              int ndisagree)
{
    if (nroots > 0) {
        double c[3] = {sum[0] / nroots, sum[1] / nroots, sum[2] / nroots};
        double room = CENTROID_SAG_ERRORS * (fl->max_error + fl->straddle_shift);
        if (!(ism_sample_dist(s, c) <= room))
            return false;
    }
    bool halves = min_side(lo, hi) <= GRAPH_HALVES_ERRORS * fl->max_error;
    if (!(halves ? ism_graph_certified(s->tape, jet, lo, hi, &s->n_interval, NULL)
                 : ism_graph_certified_whole(s->tape, jet, lo, hi, &s->n_interval)))
        return false;
    return edges_rootless(s, fl, k, disagree, ndisagree);
}

static double min_side(const double lo[3], const double hi[3])
{
    double size = hi[0] - lo[0];
    for (int a = 1; a < 3; a++)
        if (hi[a] - lo[a] < size)
            size = hi[a] - lo[a];
    return size;
}

static bool judged_by_measure(const ism_flatness *fl, const double lo[3], const double hi[3])
{
    return fl->max_error > 0 && min_side(lo, hi) <= CREASE_CELL_ERRORS * fl->max_error;
}

/* All eight corner values of one sign, none zero: a node with no polygon to measure. */
static bool one_sign(const double f[8])
{
    int sign = ism_sign(f[0]);
    for (int c = 1; c < 8; c++)
        if (ism_sign(f[c]) != sign)
            return false;
    return sign != 0;
}

/* ism_plot_test's result `pass`, for a node that may be blind (one_sign, judged by measure):
 * whether it is blind is read from its corner normals n only once it passed — a node that
 * fails is searched anyway. A node of one sign has no crossed edge, so it passes only at the
 * crease test or with no root (the two callers). */
static bool passes(bool pass, bool may_be_blind, const double (*n)[3], double normal_cos,
                   bool *blind)
{
    if (pass && may_be_blind)
        *blind = !normals_agree(n, normal_cos);
    return pass;
}

bool ism_plot_test(ism_sampler *s, ism_ivjet_ws *jet, const ism_flatness *fl,
                   const double lo[3], const double hi[3], const ism_corners *k, bool *blind)
{
    if (blind)
        *blind = false;
    const double (*p)[3] = k->p, *f = k->f;
    double n[8][3];
    memcpy(n, k->g, sizeof n);
    bool critical = false; /* a corner where ∇f vanishes (or is undefined) */
    for (int c = 0; c < 8; c++) {
        double len = ism_normalise3(n[c]);
        if (!isfinite(f[c]))
            return false; /* an undefined corner: look closer */
        critical |= !(len > 0) || !isfinite(len);
    }
    double size = min_side(lo, hi);
    bool measured_only = judged_by_measure(fl, lo, hi);
    /* The horn cyclide at E = 0.016, depth 9 (cell 0.0625), box moved by (0.37, −0.23, 0.41)
     * of a cell: its horns, y²/96 across at y from the point (10, 0, 0), thinner than E within
     * |y| < 1.26, passed through such nodes unseen (open loops ~1 short of the point, the
     * point not joined: χ 4 in 3 pieces instead of 1 in 1). Nodes whose corner gradients
     * agree are left out, as the test without a bound leaves them: a tube inside a node turns
     * them apart. */
    bool may_be_blind = blind && measured_only && one_sign(f);
    /* A crease cell is judged by its branches' own gradients (crease_cell), so a corner
     * where f's gradient vanishes is left to it: on the dominated branch, off the surface,
     * the live branch's certificate decides (max(|p|² − 1, −0.3 − x²/100) in the box ±1.3:
     * the lattice plane x = 0 puts corners where ∇(−0.3 − x²/100) = 0 inside the sphere,
     * and the nodes round them were split as singular whatever E, 1,016 triangles against
     * the sphere's 344 at E 3e-2). Elsewhere such a corner is singular or a critical point
     * of f the node may hide: look closer. */
    int crease = fl->max_error > 0 ? crease_cell(s, jet, fl, lo, hi, k, critical) : -1;
    if (crease >= 0)
        return passes(crease, may_be_blind, n, fl->normal_cos, blind);
    if (critical)
        return false;
    /* under an error bound a node whose corners disagree may still be one graph (graph
     * cert.h): then its roots, faces and measured error decide (graph_node_passes) */
    bool graph = false;
    if (!measured_only && !normals_agree(n, fl->normal_cos)) {
        if (!(fl->max_error > 0))
            return false;
        graph = true;
    }
    bool allowed = false; /* measured_only let an edge or a face through (the corners are
                             asked at the end: crossing_ok) */

    double roots[12][3], centroid[3] = {0, 0, 0};
    int nroots = 0, face_cross[6] = {0}, ndisagree = 0, disagree[12];
    unsigned neg, zero; /* the corners below 0, at 0 */
    ism_corner_sign_masks(f, &neg, &zero);
    /* an edge with a corner at 0 has no root here (the edge lies in f = 0), or the corner's
     * (below); of the others, those of one sign first, in edge order */
    unsigned off_zero = 0xfffu & ~ism_edges_touching(zero);
    for (unsigned es = off_zero & ~ism_edges_across(neg); es; es &= es - 1) {
        int e = __builtin_ctz(es), c0 = ism_cube_edges[e][0], c1 = ism_cube_edges[e][1];
        /* signs agree, gradients do not: maybe two roots (a small node under an error
         * bound leaves them to the edge roots and the measurement, below) */
        if (ism_dot3(n[c0], n[c1]) <= fl->gradient_test) {
            if (!measured_only && !graph)
                return false;
            allowed |= measured_only;
            disagree[ndisagree++] = e;
        }
    }
    for (unsigned es = off_zero & ism_edges_across(neg); es; es &= es - 1) { /* crossed */
        int c0, c1, faces[2];
        ism_cube_edge(__builtin_ctz(es), &c0, &c1, faces);
        /* One secant step is enough to judge flatness: the exact roots come later. */
        double t = f[c0] / (f[c0] - f[c1]); /* neither is 0 (above) */
        for (int a = 0; a < 3; a++) {
            roots[nroots][a] = p[c0][a] + t * (p[c1][a] - p[c0][a]);
            centroid[a] += roots[nroots][a];
        }
        nroots++;
        face_cross[faces[0]]++;
        face_cross[faces[1]]++;
    }
    /* A corner exactly on f = 0 (with a gradient: the check above) is one root of the node,
     * on the faces the surface enters there (ism_zero_corner_faces). Read once per edge, a
     * face the surface enters at that corner and leaves by another edge counted three
     * crossings and failed as a saddle at every level down to CREASE_CELL_ERRORS E: the
     * Whitney umbrella x² = y² z in its own box ±1 passes through lattice corners along
     * whole lines (x = ±y / 2 on z = 1/4, x = ±y on z = 1, x = 0 on z = 0, ...), and the
     * nodes along them all went to that level: 32,488 triangles against ~3,700 in boxes
     * moved off the lattice (default bound, depth 10). */
    for (int c = 0; c < 8; c++) {
        unsigned zf = f[c] == 0 ? ism_zero_corner_faces(f, c) : 0;
        if (!zf)
            continue;
        for (int a = 0; a < 3; a++) {
            roots[nroots][a] = p[c][a];
            centroid[a] += p[c][a];
        }
        nroots++;
        for (int fc = 0; fc < 6; fc++)
            face_cross[fc] += (zf >> fc) & 1;
    }
    for (int k = 0; k < 6; k++)
        if (face_cross[k] > 2) {
            if (!measured_only)
                return false; /* a saddle on a face: two curves, look closer */
            allowed = true;
        }
    if (graph && !graph_node_passes(s, jet, fl, lo, hi, k, centroid, nroots, disagree,
                                    ndisagree))
        return false;
    if (nroots == 0) {
        /* no edge crossed: two roots on an edge are the only sign of the surface here
         * (a tube or a wedge tip between the corners), so it is looked for */
        return passes(edges_rootless(s, fl, k, disagree, ndisagree), may_be_blind, n,
                      fl->normal_cos, blind);
    }
    /* polygons the allowances let through: across a crease, two graphs proven (asked last,
       of a node that passes) */
    double err;
    if (fl->max_error > 0 &&
        ism_cell_error(s, k, fl->max_error, fl->straddle_shift, fl->box, &err))
        return err <= fl->max_error &&
               (!measured_only || crossing_ok(s, jet, fl, lo, hi, n, allowed));
    if (graph)
        return false; /* polygons the measurement cannot follow: the corner test's path */
    for (int a = 0; a < 3; a++)
        centroid[a] /= nroots;

    double normal[3] = {0, 0, 0};
    for (int c = 0; c < 8; c++)
        for (int a = 0; a < 3; a++)
            normal[a] += n[c][a];
    ism_normalise3(normal);
    double tol = ism_flat_tolerance(fl->plane_frac, fl->abs_tol, size);
    if (fl->max_error > 0)
        tol = fl->max_error; /* polygons cell_error cannot follow: the paper's tests at E */
    for (int r = 0; r < nroots; r++) {
        double d[3] = {roots[r][0] - centroid[0], roots[r][1] - centroid[1],
                       roots[r][2] - centroid[2]};
        if (fabs(ism_dot3(normal, d)) > tol)
            return false;
    }
    double g[3];
    double fc = ism_sample_grad(s, centroid, g);
    double gl = ism_norm3(g);
    return gl > 0 && fabs(fc) / gl <= tol &&
           (!measured_only || crossing_ok(s, jet, fl, lo, hi, n, allowed));
}

double ism_flat_tolerance(double plane_frac, double abs_tol, double size)
{
    double tol = plane_frac * size;
    return tol > abs_tol ? abs_tol : tol;
}
