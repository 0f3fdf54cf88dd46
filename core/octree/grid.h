/* grid.h — the integer lattice under the octree. A point of the lattice has integer
 * coordinates 0..2^depth on each axis (the depth the polygoniser may reach, below its maximum depth where a piece is thinner than a cell); a cell at
 * level L spans 2^(depth-L) lattice steps. Every world coordinate of a lattice point comes
 * from grid_coord(), so the same lattice point always has bit-identical world coordinates
 * in every cell that mentions it — the basis of exact welding. */
#ifndef ISM_GRID_H
#define ISM_GRID_H

#include <stdint.h>

/* Deepest octree level the lattice supports: coordinates up to 2^19 take 20 bits, and the
 * break-point keys (breaks.c: 2 + 3 × 20 bits) and node keys (refine.c: 5 + 3 × 19 bits)
 * still fit in 64. The polygoniser's depth.max stays at most ISM_MAX_DEPTH_LIMIT; the levels
 * below it are for pieces thinner than a cell (ISM_THIN_EXTRA_DEPTH). */
#define ISM_GRID_MAX_DEPTH 19

typedef struct ism_grid {
    int depth;          /* maximum octree depth: lattice has 2^depth steps per axis */
    double lo[3];       /* world coordinates of lattice point (0,0,0) */
    double step[3];     /* world size of one lattice step on each axis */
} ism_grid;

/* A lattice point or a cell origin. */
typedef struct ism_ipt {
    int32_t v[3];
} ism_ipt;

void ism_grid_init(ism_grid *g, const double box[6], int depth);

static inline double ism_grid_coord(const ism_grid *g, int axis, int32_t i)
{
    return g->lo[axis] + g->step[axis] * (double)i;
}

static inline void ism_grid_point(const ism_grid *g, ism_ipt p, double out[3])
{
    for (int k = 0; k < 3; k++)
        out[k] = ism_grid_coord(g, k, p.v[k]);
}

/* Lattice steps spanned by a cell at this level. */
static inline int32_t ism_grid_cell_steps(const ism_grid *g, int level)
{
    return (int32_t)1 << (g->depth - level);
}

/* A lattice point as one nonzero 64-bit key: ISM_LATTICE_KEY_BITS per coordinate (the
 * lattice's 2^ISM_GRID_MAX_DEPTH + 1 points per axis fit in 21), plus one so that 0 marks an
 * empty slot. */
#define ISM_LATTICE_KEY_BITS 21
static inline uint64_t ism_lattice_key(const int32_t p[3])
{
    uint64_t k = (uint64_t)p[0] << 2 * ISM_LATTICE_KEY_BITS;
    return (k | (uint64_t)p[1] << ISM_LATTICE_KEY_BITS | (uint64_t)p[2]) + 1;
}

/* The lattice point of a key: the inverse of ism_lattice_key. */
static inline void ism_lattice_point(uint64_t key, int32_t p[3])
{
    uint64_t k = key - 1, mask = ((uint64_t)1 << ISM_LATTICE_KEY_BITS) - 1;
    p[0] = (int32_t)(k >> 2 * ISM_LATTICE_KEY_BITS & mask);
    p[1] = (int32_t)(k >> ISM_LATTICE_KEY_BITS & mask);
    p[2] = (int32_t)(k & mask);
}

/* Spreads a key's bits over the whole word, for tables indexed by its low bits. */
static inline uint64_t ism_cache_mix(uint64_t k)
{
    k ^= k >> 31;
    k *= 0x9e3779b97f4a7c15ull;
    return k ^ (k >> 29);
}

/* The smallest world size of a cell at this level (over the three axes). */
double ism_grid_cell_size(const ism_grid *g, int level);

#endif
