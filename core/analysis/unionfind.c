/* unionfind.c — disjoint sets over integer ids for the analysis (cones of faces, components):
 * path halving, and the smaller root always wins, so every parent is at most its child and
 * a set's root is its smallest member (which makes numbering the sets deterministic). */
#include "core/analysis/unionfind.h"

uint32_t ism_an_uf_find(uint32_t *parent, uint32_t i)
{
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

bool ism_an_uf_union(uint32_t *parent, uint32_t i, uint32_t j)
{
    uint32_t ri = ism_an_uf_find(parent, i), rj = ism_an_uf_find(parent, j);
    if (ri == rj)
        return false;
    if (ri < rj)
        parent[rj] = ri;
    else
        parent[ri] = rj;
    return true;
}
