/* test_corners_scalar.c — corners.h's scalar sign masks (the branch of a build without SSE2,
 * which an x86-64 build never compiles otherwise: __SSE2__ is undefined for this unit alone)
 * against the compares, as test_corners.c checks the SSE2 ones (corner_signs.h). */
#undef __SSE2__
#include "core/octree/corners.h"
#include "corner_signs.h"

#if defined(_mm_movemask_pd) || defined(_EMMINTRIN_H_INCLUDED)
#error "the scalar sign masks are meant here"
#endif

Test(corners_scalar, sign_masks_are_the_compares_corner_by_corner)
{
    check_sign_masks();
}
