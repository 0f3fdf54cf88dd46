/* corners.c — the numbering of a node's edges and faces (see corners.h). */
#include "core/octree/corners.h"

const unsigned char ism_cube_edges[12][4] = {
    {0, 1, 2, 4}, {2, 3, 3, 4}, {4, 5, 2, 5}, {6, 7, 3, 5}, /* along x */
    {0, 2, 4, 0}, {4, 6, 5, 0}, {1, 3, 4, 1}, {5, 7, 5, 1}, /* along y */
    {0, 4, 0, 2}, {1, 5, 1, 2}, {2, 6, 0, 3}, {3, 7, 1, 3}, /* along z */
};

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
