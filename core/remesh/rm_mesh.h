/* rm_mesh.h — the quality pass's working view of a triangle mesh (rm_mesh.c): each vertex's
 * incident triangles in a slot with room to spare (so edge flips can update them in place;
 * a collapse moves a slot that overflows to the end of the array), the vertices and edges
 * that must not change, the triangles and vertices collapses removed, the per-triangle patch
 * labels, and the small geometric helpers (angles, normals) the steps share. */
#ifndef ISM_RM_MESH_H
#define ISM_RM_MESH_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/mesh/mesh.h"
#include "core/util/vec3.h"

/* Room kept in each vertex's slot beyond its starting degree: a flip adds one triangle to
 * each of two vertices, so a vertex may gain at most this many before flips stop touching it
 * (valence far above the start's is never a good triangle shape anyway). */
#define ISM_RM_SLACK 6

typedef struct rm_mesh {
    ism_mesh *m;
    uint32_t *start;          /* slot of vertex v: vt[start[v] .. start[v] + room[v]) */
    uint32_t *room;           /* capacity of vertex v's slot */
    uint32_t *count;          /* triangles in vertex v's slot */
    uint32_t *vt;             /* incident triangle indices */
    size_t nvt, cap_vt;       /* entries of vt handed out to slots, allocated */
    uint8_t *locked;          /* per vertex: never moved (RM_PINNED: never removed either,
                                 a given point's vertex or a segment's end) */
    uint8_t *gone;            /* per vertex: removed by a collapse (in no triangle) */
    uint8_t *dead;            /* per triangle: removed by a collapse (in no slot) */
    uint32_t *origin;         /* per triangle: the triangle before the pass it was cut from
                                 (itself, for those the pass started with) */
    size_t cap_verts, cap_tris; /* room in every per-vertex / per-triangle array (and the
                                 mesh's) for vertices and triangles that insertions add */
    const uint32_t *label;    /* per triangle before the pass (index by origin), or NULL:
                                 flips only between equal labels */
    uint64_t *locked_edges;   /* sorted keys (rm_edge_key) of edges never flipped */
    size_t nlocked_edges;
} rm_mesh;

/* A locked vertex's value of r->locked when it may not even be merged along a crease
 * (rm_collapse.c): a given point's vertex, a segment's end. */
#define RM_PINNED 2

/* Builds the incidence of m (r zeroed by the caller), with room for extra vertices and
 * 2 × extra triangles more (in m too). False when out of memory. */
bool rm_mesh_build(rm_mesh *r, ism_mesh *m, size_t extra);

/* The i-th triangle at vertex v (i < r->count[v]). */
static inline uint32_t rm_slot(const struct rm_mesh *r, uint32_t v, uint32_t i)
{
    return r->vt[r->start[v] + i];
}

/* The label of triangle t (0 without labels). */
static inline uint32_t rm_label(const struct rm_mesh *r, uint32_t t)
{
    return r->label ? r->label[r->origin[t]] : 0;
}
void rm_mesh_free(rm_mesh *r);

/* The key of the undirected edge {a, b}. */
static inline uint64_t rm_edge_key(uint32_t a, uint32_t b)
{
    return a < b ? ((uint64_t)a << 32) | b : ((uint64_t)b << 32) | a;
}

/* True when key is among the n sorted keys (binary search). */
bool rm_keys_has(const uint64_t *keys, size_t n, uint64_t key);

/* True when {a, b} is in the locked edge list. */
bool rm_edge_locked(const rm_mesh *r, uint32_t a, uint32_t b);

/* The triangles of edge {a, b}: *n gets how many there are (all of them counted), t[0..1]
 * the first two: t[0] runs a -> b, t[1] runs b -> a when the edge is an oriented manifold
 * edge (*n == 2 and the function returns true). */
bool rm_edge_triangles(const rm_mesh *r, uint32_t a, uint32_t b, uint32_t t[2], int *n);

/* Position k (0..2) of vertex v in triangle t, or -1. */
static inline int rm_corner(const ism_mesh *m, uint32_t t, uint32_t v)
{
    for (int k = 0; k < 3; k++)
        if (m->tri[3 * t + k] == v)
            return k;
    return -1;
}

/* Removes triangle t from / adds it to vertex v's slot. Adding fails when the slot is full. */
void rm_slot_remove(rm_mesh *r, uint32_t v, uint32_t t);
bool rm_slot_add(rm_mesh *r, uint32_t v, uint32_t t);
/* True when v's slot has room for one more triangle. */
bool rm_slot_room(const rm_mesh *r, uint32_t v);
/* Makes room for n more triangles in v's slot (moving it to the end of vt when it is too
 * small). False when out of memory or vt would pass 2^32 entries. */
bool rm_slot_reserve(rm_mesh *r, uint32_t v, uint32_t n);

/* A triangle with an angle at least this large (degrees) is a cap: its apex lies almost on
 * the opposite side, so its normal is rounding noise and says nothing about a bend
 * (klein-bottle: 0.1°-1° caps along the double curve's tubes, their flips refused as "bent",
 * steiner-roman: caps beside the double lines taken for creases, their vertices locked). */
#define ISM_RM_CAP_DEG 160.0

/* Geometry (the small helpers inline: the pass calls them for every triangle of a fan at
 * every step). */
/* (b - a) x (c - a), not normalised; returns its length. */
static inline double rm_cross(const double *a, const double *b, const double *c, double n[3])
{
    ism_tri_cross3(a, b, c, n);
    return ism_norm3(n);
}
static inline double rm_dist(const double *p, const double *q) { return ism_dist3(p, q); }
/* The angle at p between p->q and p->s (radians, 0 for a zero-length side). */
double rm_angle(const double *p, const double *q, const double *s);
/* The smallest of the triangle's three angles (radians). */
double rm_min_angle(const double *a, const double *b, const double *c);
/* Its sine (0 for a degenerate triangle): the smallest angle is at most 60°, where the sine
 * still grows with the angle, so comparisons need no arc tangent. */
/* The same from twice the area and the three sides (for callers that have them already). */
static inline double rm_sine_of(double twice_area, double ab, double bc, double ca)
{
    /* 2 area = |AB x AC| = product of the two sides at the smallest angle × its sine; those
     * are the two longest sides */
    double shortest = bc < ca ? bc : ca, prod = ab * bc * ca; /* no libm fmin call */
    shortest = ab < shortest ? ab : shortest;
    return prod > 0 ? twice_area * shortest / prod : 0;
}
static inline double rm_min_sine(const double *a, const double *b, const double *c)
{
    double n[3], twice_area = rm_cross(a, b, c, n);
    return rm_sine_of(twice_area, rm_dist(a, b), rm_dist(b, c), rm_dist(c, a));
}
/* True when the triangle's largest angle is at least ISM_RM_CAP_DEG. */
bool rm_is_cap(const double *a, const double *b, const double *c);

#endif
