/* corners.h — a node's 8 corners with f and ∇f there, and how its 12 edges and 6 faces are
 * numbered (corners.c). Shared by the flatness test and the error measure of a node. */
#ifndef ISM_CORNERS_H
#define ISM_CORNERS_H

#include <stdint.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

struct ism_node_memo;

/* f and ∇f at a node's 8 corners (corner c: bit 0 = x, bit 1 = y, bit 2 = z), the corners'
 * lattice keys (grid.h's ism_lattice_key) and the thread's memo of what the flatness test
 * finds at lattice points and on lattice edges (cell_cache.h's ism_node_memo; NULL: none,
 * keys unused). */
typedef struct ism_corners {
    double p[8][3], f[8], g[8][3];
    uint64_t key[8];
    const struct ism_node_memo *memo;
} ism_corners;

/* Edge e (0..11) of a node: its corners c0 -> c1 (c1 one step along axis a = e / 4) and the
 * two faces it lies on (face = axis * 2 + side). With r = e % 4, o1 = (a + 1) % 3 and
 * o2 = (a + 2) % 3: c0 = (r & 1) << o1 | (r >> 1 & 1) << o2, c1 = c0 | 1 << a, the faces
 * o1 * 2 + (r & 1) and o2 * 2 + (r >> 1 & 1); written out in ism_cube_edges (corners.c) and
 * read inline: the plot test's and the cells' edge loops ask for it millions of times (as a
 * call with those divisions, 41M instructions of Barth's sextic at E 1e-2). */
extern const unsigned char ism_cube_edges[12][4]; /* c0, c1, faces[0], faces[1] */

static inline void ism_cube_edge(int e, int *c0, int *c1, int faces[2])
{
    const unsigned char *t = ism_cube_edges[e];
    *c0 = t[0];
    *c1 = t[1];
    faces[0] = t[2];
    faces[1] = t[3];
}

/* The edges (bit e of the result) of per-axis corner masks x, y, z: bit c of x marks edge
 * c -> c | 1 (c0 = 0, 2, 4, 6: edges 0..3), of y edge c -> c | 2 (c0 = 0, 4, 1, 5: edges 4..7),
 * of z edge c -> c | 4 (c0 = 0..3: edges 8..11), ism_cube_edges' order. */
static inline unsigned ism_edge_bits(unsigned x, unsigned y, unsigned z)
{
    unsigned ex = (x & 1) | (x >> 1 & 2) | (x >> 2 & 4) | (x >> 3 & 8);
    unsigned ey = (y & 1) | (y >> 3 & 2) | (y << 1 & 4) | (y >> 2 & 8);
    return ex | ey << 4 | (z & 0xf) << 8;
}

/* ism_edges_across of each corner mask 0..255, written out (corners.c): the three shifts'
 * ~25 instructions were asked of every tested node by the plot test, the cells and the root
 * prefetch (Barth's sextic at E 0.0259, callgrind, one thread: ~3M of the build's). */
extern const uint16_t ism_edges_across_of[256];

/* The edges whose two corners differ in corner mask m (bit c: corner c, m < 256), e.g. those
 * a sign change crosses when m marks the corners below 0: the 12-edge loop's test, by
 * ism_edges_across_of. */
static inline unsigned ism_edges_across(unsigned m)
{
    return ism_edges_across_of[m & 0xffu];
}

/* The edges with at least one corner in corner mask m (none for m = 0, the common case: a
 * corner exactly on f = 0 is rare). */
static inline unsigned ism_edges_touching(unsigned m)
{
    if (!m)
        return 0;
    return ism_edge_bits((m | m >> 1) & 0x55, (m | m >> 2) & 0x33, (m | m >> 4) & 0x0f);
}

/* The corners (bit c: corner c) where f (the 8 values) is below 0 into *neg, exactly 0 into
 * *zero; NaN is in neither (reads as positive). Two corners a compare under SSE2 (cmplt /
 * cmpeq are C's < and == lane by lane: false on NaN, -0 == 0): Barth's sextic at E 0.00389
 * (callgrind, one thread) spent ~12 instructions a corner in the unrolled scalar loop, asked
 * of every tested node by the plot test, the cells and the root prefetch. */
static inline void ism_corner_sign_masks(const double f[8], unsigned *neg, unsigned *zero)
{
    unsigned n = 0, z = 0;
#if defined(__SSE2__)
    const __m128d zero_v = _mm_setzero_pd();
#pragma GCC unroll 4
    for (int c = 0; c < 8; c += 2) {
        __m128d v = _mm_loadu_pd(f + c);
        n |= (unsigned)_mm_movemask_pd(_mm_cmplt_pd(v, zero_v)) << c;
        z |= (unsigned)_mm_movemask_pd(_mm_cmpeq_pd(v, zero_v)) << c;
    }
#else
#pragma GCC unroll 8 /* a loop of 8 compares at -O2: ~180 instructions a node (prefetch) */
    for (int c = 0; c < 8; c++) {
        n |= (unsigned)(f[c] < 0) << c;
        z |= (unsigned)(f[c] == 0) << c;
    }
#endif
    *neg = n;
    *zero = z;
}

/* The edges holding a single root of f between their corners (f's 8 values): a sign change
 * with neither end 0 (a corner on f = 0 is a root of its own: ism_zero_corner_faces). NaN
 * reads as positive. The rule of the flatness test's edge roots (cell_error.c) and of the
 * build's prefetch of them (level_prefetch.c). */
static inline unsigned ism_single_root_edges(const double f[8])
{
    unsigned neg, zero;
    ism_corner_sign_masks(f, &neg, &zero);
    return ism_edges_across(neg) & ~ism_edges_touching(zero);
}

/* Corner c where f is exactly 0 (a lattice point on the surface, its gradient not zero): the
 * faces (bit face) the surface enters there, those whose two edges at c lead to corners of
 * opposite signs (f ≈ ∇f · (q − c) near c: where both lead to one sign the face's quadrant
 * lies on that side and the surface only touches it at c), so 0 or 2 of them. A neighbour
 * also on f = 0 (the edge between lies in the surface, or is a chord of it) reads as on the
 * positive side, as if f were raised by an infinitesimal: of the nodes on both sides of a
 * lattice plane of the surface the negative one takes the plane's polygon, and a node the
 * surface only touches along an edge (the Whitney umbrella's fold line x = 0 on z = 0, from
 * below) has none. f: the 8 values. */
unsigned ism_zero_corner_faces(const double f[8], int c);

#endif
