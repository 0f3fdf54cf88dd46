/* corners.c — the numbering of a node's edges and faces (see corners.h). */
#include "core/octree/corners.h"

void ism_cube_edge(int e, int *c0, int *c1, int faces[2])
{
    int axis = e / 4, rest = e % 4;
    int o1 = (axis + 1) % 3, o2 = (axis + 2) % 3;
    int base = ((rest & 1) << o1) | (((rest >> 1) & 1) << o2);
    *c0 = base;
    *c1 = base | (1 << axis);
    faces[0] = o1 * 2 + (rest & 1);
    faces[1] = o2 * 2 + ((rest >> 1) & 1);
}

unsigned ism_zero_corner_faces(const double f[8], int c)
{
    unsigned faces = 0;
    for (int t = 0; t < 3; t++) { /* the face across axis t, spanned by the other two */
        int a = c ^ (1 << (t + 1) % 3), b = c ^ (1 << (t + 2) % 3);
        if ((f[a] < 0) != (f[b] < 0)) /* 0 reads as positive */
            faces |= 1u << (t * 2 + ((c >> t) & 1));
    }
    return faces;
}
