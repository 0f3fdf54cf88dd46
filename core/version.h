/* version.h — the version of isomesh's mesher. It is part of every cache key: change
 * ISM_MESHER_VERSION whenever the polygoniser or the analysis could produce a different mesh
 * or different attributes for the same request, so a new algorithm never serves old meshes. */
#ifndef ISM_VERSION_H
#define ISM_VERSION_H

#define ISM_VERSION "0.1.0"
#define ISM_MESHER_VERSION "mesher-36"
/* How a preview ("preview": true) searches for pieces hidden from the cells' corners: part of
 * a preview's cache key only, so previews made before the search changed are not served. */
#define ISM_PREVIEW_SEARCH "thin-coarse"

#endif
