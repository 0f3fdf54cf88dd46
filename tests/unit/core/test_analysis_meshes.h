/* test_analysis_meshes.h — hand-built meshes for the analysis tests, each with topology known
 * from its construction (stated beside each builder). */
#ifndef TEST_ANALYSIS_MESHES_H
#define TEST_ANALYSIS_MESHES_H

#include "core/mesh/mesh.h"

/* Unit cube [0,1]³, 8 vertices, 12 outward triangles. */
void ta_cube(ism_mesh *m);
/* Cone of n triangles around the existing vertex apex, with a new ring of n vertices on the
 * unit circle at height h (n triangles, n ring edges on the boundary). */
void ta_fan(ism_mesh *m, uint32_t apex, int n, double h);
/* Disc: a centre and a ring of n vertices, n triangles. */
void ta_disc(ism_mesh *m, int n);
/* Möbius strip of n quads (2n triangles), 2n vertices. */
void ta_moebius(ism_mesh *m, int n);
/* Torus grid of nu × nv quads on the torus of radii R (around z) and r: nu·nv vertices,
 * 2·nu·nv triangles, vertices exactly on the torus. */
void ta_torus(ism_mesh *m, int nu, int nv, double R, double r);
/* Square grid of k × k cells spanning [-1,1]² in the plane of axes (a, b) (0 = x, 1 = y,
 * 2 = z), welded with the vertices already in m that sit at the same place. */
void ta_plane_grid(ism_mesh *m, int a, int b, int k);
/* Icosahedron subdivided `levels` times, every vertex projected onto the sphere of radius r
 * (20·4^levels triangles). */
void ta_icosphere(ism_mesh *m, int levels, double r);

uint32_t ta_vertex(ism_mesh *m, double x, double y, double z);
void ta_triangle(ism_mesh *m, uint32_t a, uint32_t b, uint32_t c);

#endif
