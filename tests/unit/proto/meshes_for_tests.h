/* meshes_for_tests.h — small meshes built in the proto tests (independent of the
 * polygoniser): a flat grid (one boundary loop), a torus (closed, manifold), two crossing
 * planes (a line of non-manifold edges), two tetrahedra touching at a vertex (a non-manifold
 * point). */
#ifndef ISM_TEST_MESHES_H
#define ISM_TEST_MESHES_H

#include <stdbool.h>
#include "core/mesh/mesh.h"

/* n x n quads over [0,1]² at z = 0, normals +z: 2n² triangles, boundary loop of 4n edges. */
void test_mesh_grid(ism_mesh *m, int n);

/* Torus (R, r) with nu x nv quads: 2 nu nv triangles, closed, normals outwards. */
void test_mesh_torus(ism_mesh *m, int nu, int nv, double R, double r);

/* Plane z = 0 and plane y = 0 over [-1,1]² (n x n quads each, n even) sharing the vertices
 * on the x axis: n non-manifold edges with four triangles each. */
void test_mesh_crossing_planes(ism_mesh *m, int n);

/* Two closed tetrahedra sharing one vertex (the origin): a non-manifold point. */
void test_mesh_touching_tetrahedra(ism_mesh *m);

#endif
