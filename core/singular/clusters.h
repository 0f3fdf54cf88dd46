/* clusters.h — connected clusters of the search's finest candidate boxes: two boxes are
 * neighbours when they share a face, an edge or a corner (26-connectivity). */
#ifndef ISM_SING_CLUSTERS_H
#define ISM_SING_CLUSTERS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/singular/locus.h"

/* Labels boxes[0..n) (finest boxes of the search with options o; boxes larger than a finest
 * cell are their own cluster): label[i] = cluster number, numbered 0.. in the order of
 * each cluster's first box. Returns the number of clusters, or (size_t)-1 when out of
 * memory. */
size_t ism_sing_clusters(const ism_locus_options *o, const ism_lbox *boxes, size_t n,
                         uint32_t *label);

#endif
