/* breaks_near.c — the leaves a round's polygonised leaves can see (breaks_near.h), found on a
 * coarse bit grid over the lattice with a summary level beside it: the polygonised leaves
 * mark the cells of their shells, every other leaf asks its own shell's. */
#include "core/octree/breaks_near.h"

#include <stdlib.h>
#include <string.h>

/* A coarse grid of bits over the lattice, cells the size of the commonest leaf (plus one
 * for the far boundary). Leaves' interiors are apart, so two leaves that touch meet on both
 * boundaries, at a point q whose cell q >> shift lies on the shell of either box's range of
 * cells (q's coordinate at a box's end gives the range's end). A polygonised leaf marks the
 * cells of its shell; another leaf is taken when a cell of its own shell is marked (no larger
 * than a cell: all of its 1 to 8). Every leaf touching a polygonised one is taken, with some
 * more nearby. */
/* A leaf whose box spans more than this many cells on an axis is taken without asking (its
 * shell's cells are many, its 8 corners few): on Barth's sextic at 1e-2 the 1,100 leaves of
 * levels 3 and 4 beside 36,000 of levels 5 to 8. */
#define NEAR_BIG 4
/* Cells per axis at most (2^8: 2 MB of bits), whatever the leaves. */
#define NEAR_MAX_BITS 8

/* Beside it, a summary grid of cells 2^NEAR_SUM_SHIFT cells wide: marked at the summary cell
 * of every marked cell and the 7 below it, so the summary cell of a leaf's lowest corner is
 * marked whenever a cell of a leaf no wider than a summary cell is (that cell's summary cell
 * is the corner's or one above on each axis): one lookup answers most leaves, which touch
 * nothing polygonised. That holds only for leaves at most 2^NEAR_SUM_SHIFT cells wide;
 * near_asked checks the width itself, so NEAR_BIG may exceed it (wider leaves would then
 * skip the summary and walk their shell), but as set every leaf it asks is that narrow. */
#define NEAR_SUM_SHIFT 2
_Static_assert(NEAR_BIG <= 1 << NEAR_SUM_SHIFT, "every asked leaf takes the one summary lookup");

typedef struct near_grid {
    uint64_t *mark, *sum;
    int shift;
    size_t side, sside; /* cells per axis, summary cells per axis */
} near_grid;

static bool bit_get(const uint64_t *bits, size_t side, size_t x, size_t y, size_t z)
{
    size_t c = (z * side + y) * side + x;
    return (bits[c >> 6] >> (c & 63)) & 1;
}

static void bit_set(uint64_t *bits, size_t side, size_t x, size_t y, size_t z)
{
    size_t c = (z * side + y) * side + x;
    bits[c >> 6] |= (uint64_t)1 << (c & 63);
}

/* Calls fn(g, x, y, z) for each cell on the shell of the range lo .. hi (every cell of it
 * with a coordinate at an end); stops at the first call returning true, and returns that. */
static bool on_shell(near_grid *g, const size_t lo[3], const size_t hi[3],
                     bool (*fn)(near_grid *, size_t, size_t, size_t))
{
    for (size_t z = lo[2]; z <= hi[2]; z++)
        for (size_t y = lo[1]; y <= hi[1]; y++) {
            bool side = z == lo[2] || z == hi[2] || y == lo[1] || y == hi[1];
            size_t step = side || hi[0] == lo[0] ? 1 : hi[0] - lo[0];
            for (size_t x = lo[0]; x <= hi[0]; x += step)
                if (fn(g, x, y, z))
                    return true;
        }
    return false;
}

static bool mark_cell(near_grid *g, size_t x, size_t y, size_t z)
{
    bit_set(g->mark, g->side, x, y, z);
    return false;
}

/* Marks summary cell (x, y, z) and the 7 below it. */
static bool mark_summary(near_grid *g, size_t x, size_t y, size_t z)
{
    for (int d = 0; d < 8; d++) {
        size_t sx = x - (d & 1), sy = y - (d >> 1 & 1), sz = z - (d >> 2);
        if (sx < g->sside && sy < g->sside && sz < g->sside) /* below 0 wraps past sside */
            bit_set(g->sum, g->sside, sx, sy, sz);
    }
    return false;
}

static bool marked(near_grid *g, size_t x, size_t y, size_t z)
{
    return bit_get(g->mark, g->side, x, y, z);
}

/* The cells node nd's closed box meets, per axis: lo[a] .. hi[a]. */
static void near_range(const near_grid *g, const ism_octree *t, const ism_node *nd,
                       size_t lo[3], size_t hi[3])
{
    int32_t s = ism_grid_cell_steps(&t->grid, nd->level);
    for (int a = 0; a < 3; a++) {
        lo[a] = (size_t)(nd->org[a] >> g->shift);
        hi[a] = (size_t)((nd->org[a] + s) >> g->shift);
    }
}

/* Marks the cells on the shell of nd's range and, in the summary, their summary cells (the
 * summary range's shell) with the 7 below each (set); or tells whether a cell on the shell is
 * marked. */
static bool near_shell(near_grid *g, const ism_octree *t, const ism_node *nd, bool set)
{
    size_t lo[3], hi[3];
    near_range(g, t, nd, lo, hi);
    if (!set)
        return on_shell(g, lo, hi, marked);
    on_shell(g, lo, hi, mark_cell);
    for (int a = 0; a < 3; a++)
        lo[a] >>= NEAR_SUM_SHIFT, hi[a] >>= NEAR_SUM_SHIFT;
    on_shell(g, lo, hi, mark_summary);
    return false;
}

/* Does leaf nd's shell meet a marked cell (or is it too large to ask)? */
static bool near_asked(near_grid *g, const ism_octree *t, const ism_node *nd)
{
    int32_t cells = ism_grid_cell_steps(&t->grid, nd->level) >> g->shift;
    if (cells > NEAR_BIG)
        return true;
    if (cells <= 1 << NEAR_SUM_SHIFT &&
        !bit_get(g->sum, g->sside, (size_t)nd->org[0] >> (g->shift + NEAR_SUM_SHIFT),
                 (size_t)nd->org[1] >> (g->shift + NEAR_SUM_SHIFT),
                 (size_t)nd->org[2] >> (g->shift + NEAR_SUM_SHIFT)))
        return false;
    return near_shell(g, t, nd, false);
}

/* The level most leaves have, at most NEAR_MAX_BITS. */
static int commonest_level(const ism_octree *t, const int32_t *leaves, size_t nleaves)
{
    size_t count[ISM_GRID_MAX_DEPTH + 1] = {0};
    for (size_t k = 0; k < nleaves; k++)
        count[t->nodes[leaves[k]].level]++;
    int best = 0;
    for (int l = 1; l <= NEAR_MAX_BITS && l <= t->grid.depth; l++)
        best = count[l] > count[best] ? l : best;
    return best;
}

bool ism_breaks_near(const ism_octree *t, const int32_t *leaves, size_t nleaves,
                     const int32_t *reuse, uint8_t *take)
{
    near_grid g;
    int level = commonest_level(t, leaves, nleaves);
    g.shift = t->grid.depth - level;
    g.side = ((size_t)1 << level) + 1;
    g.sside = (((size_t)1 << level) >> NEAR_SUM_SHIFT) + 1;
    g.mark = calloc((g.side * g.side * g.side + 63) / 64, sizeof *g.mark);
    g.sum = calloc((g.sside * g.sside * g.sside + 63) / 64, sizeof *g.sum);
    if (!g.mark || !g.sum) {
        free(g.mark);
        free(g.sum);
        return false;
    }
    for (size_t k = 0; k < nleaves; k++)
        if (reuse[k] < 0)
            near_shell(&g, t, &t->nodes[leaves[k]], true);
    memset(take, 0, t->n);
    for (size_t k = 0; k < nleaves; k++)
        take[leaves[k]] = reuse[k] < 0 || near_asked(&g, t, &t->nodes[leaves[k]]);
    free(g.mark);
    free(g.sum);
    return true;
}
