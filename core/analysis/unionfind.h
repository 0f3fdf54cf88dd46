/* unionfind.h — disjoint sets over integer ids (unionfind.c) for cones of faces and
 * components. */
#ifndef ISM_AN_UNIONFIND_H
#define ISM_AN_UNIONFIND_H

#include <stdint.h>
#include <stdbool.h>

/* Union-find over n elements whose roots are always the smallest member: parent[i] <= i. */
uint32_t ism_an_uf_find(uint32_t *parent, uint32_t i);
/* Joins the sets of i and j; true when they were different sets. */
bool ism_an_uf_union(uint32_t *parent, uint32_t i, uint32_t j);

#endif
