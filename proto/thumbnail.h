/* thumbnail.h — a small picture of a mesh, drawn by the project itself (the gallery's
 * thumbnails, ?format=png): the viewer's default 3/4 view fitted to the mesh, Lambert shading
 * with the viewer's surface colour outside and its warm tint inside, transparent background. */
#ifndef ISM_THUMBNAIL_H
#define ISM_THUMBNAIL_H

#include <stdbool.h>
#include <stddef.h>

#include "core/mesh/mesh.h"

#define ISM_THUMB_W 160
#define ISM_THUMB_H 120

/* The PNG (ISM_THUMB_W x ISM_THUMB_H, RGBA) of m seen from the viewer's default direction;
 * box (xmin ymin zmin xmax ymax zmax) frames an empty mesh. *png malloc'd. False when out of
 * memory. */
bool ism_thumbnail_png(const ism_mesh *m, const double box[6], unsigned char **png, size_t *len);

/* The same picture as RGBA pixels (4 * w * h bytes, malloc'd), at any size up to 2048. */
unsigned char *ism_thumbnail_rgba(const ism_mesh *m, const double box[6], int w, int h);

#endif
