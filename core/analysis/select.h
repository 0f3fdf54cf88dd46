/* select.h — the k-th smallest of an array (select.c), for medians. */
#ifndef ISM_AN_SELECT_H
#define ISM_AN_SELECT_H

#include <stddef.h>

/* The k-th smallest (0-based) of v[0..n), reordering v. n > k. */
double ism_an_select_double(double *v, size_t n, size_t k);
float ism_an_select_float(float *v, size_t n, size_t k);

#endif
