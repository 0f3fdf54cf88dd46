/* sheet_assemble.c — components of the double-sheet triangles (union-find on their
 * crossings), a stable grouping of the triangles by component, and the append to the mesh
 * with each component's area (see sheet_assemble.h). */
#include "core/singular/sheet_assemble.h"
#include "core/octree/edge_keys.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static uint32_t find_root(uint32_t *parent, uint32_t i)
{
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

/* Component number (0, 1, ... in order of first triangle) of each triangle; returns how
 * many components there are, or SIZE_MAX when out of memory. */
static size_t label_components(const ism_sheet_tris *t, uint32_t *comp)
{
    size_t nx = t->xmap.n;
    uint32_t *parent = malloc((nx ? nx : 1) * sizeof *parent);
    uint32_t *label = malloc((nx ? nx : 1) * sizeof *label);
    if (!parent || !label) {
        free(parent);
        free(label);
        return SIZE_MAX;
    }
    for (size_t i = 0; i < nx; i++) {
        parent[i] = (uint32_t)i;
        label[i] = UINT32_MAX;
    }
    for (size_t i = 0; i < t->ntris; i++)
        for (int k = 1; k < 3; k++) {
            uint32_t a = find_root(parent, t->tri[3 * i]), b = find_root(parent, t->tri[3 * i + k]);
            if (a != b)
                parent[a < b ? b : a] = a < b ? a : b;
        }
    size_t ncomp = 0;
    for (size_t i = 0; i < t->ntris; i++) {
        uint32_t r = find_root(parent, t->tri[3 * i]);
        if (label[r] == UINT32_MAX)
            label[r] = (uint32_t)ncomp++;
        comp[i] = label[r];
    }
    free(parent);
    free(label);
    return ncomp;
}

/* Appends the triangles of one component (order[first .. end)), their vertices on first
 * use; returns the area, or -1 when out of memory. */
static double append_component(const ism_sheet_tris *t, const size_t *order, size_t first,
                               size_t end, uint32_t *vertex_of, ism_mesh *mesh)
{
    double area = 0;
    for (size_t i = first; i < end; i++) {
        uint32_t v[3];
        for (int k = 0; k < 3; k++) {
            uint32_t x = t->tri[3 * order[i] + k];
            if (vertex_of[x] == UINT32_MAX)
                vertex_of[x] = ism_mesh_add_vertex(mesh, t->x[x].p, t->x[x].n);
            if ((v[k] = vertex_of[x]) == UINT32_MAX)
                return -1;
        }
        if (!ism_mesh_add_triangle(mesh, v[0], v[1], v[2]))
            return -1;
        area += ism_tri_area3(mesh->pos + 3 * v[0], mesh->pos + 3 * v[1], mesh->pos + 3 * v[2]);
    }
    return area;
}

/* Marks in drop[c] the components that are scraps: a boundary edge (an edge of one
 * triangle) and an area below min_area. False when out of memory. */
static bool find_scraps(const ism_sheet_tris *t, const uint32_t *comp, size_t ncomp,
                        double min_area, uint8_t *drop)
{
    ism_key_map edges;
    ism_key_map_init(&edges);
    uint8_t *uses = NULL;
    double *area = calloc(ncomp ? ncomp : 1, sizeof *area);
    size_t cap = 0;
    bool ok = area != NULL;
    for (size_t i = 0; ok && i < t->ntris; i++) {
        const uint32_t *v = t->tri + 3 * i;
        area[comp[i]] += ism_tri_area3(t->x[v[0]].p, t->x[v[1]].p, t->x[v[2]].p);
        for (int k = 0; ok && k < 3; k++) {
            bool added;
            uint32_t e = ism_key_map_add(&edges, ism_edge_key(v[k], v[(k + 1) % 3]), &added);
            if (e != ISM_KEY_NONE && e >= cap) {
                uint8_t *u = realloc(uses, (cap = 2 * e + 1024));
                ok = u != NULL;
                uses = u ? u : uses;
            }
            ok = ok && e != ISM_KEY_NONE;
            if (ok)
                uses[e] = added ? 1 : 2;
        }
    }
    for (size_t c = 0; ok && c < ncomp; c++)
        drop[c] = 0;
    for (size_t i = 0; ok && i < t->ntris; i++)
        for (int k = 0; k < 3; k++) {
            const uint32_t *v = t->tri + 3 * i;
            uint32_t e = ism_key_map_find(&edges, ism_edge_key(v[k], v[(k + 1) % 3]));
            if (uses[e] == 1 && area[comp[i]] < min_area)
                drop[comp[i]] = 1;
        }
    ism_key_map_free(&edges);
    free(uses);
    free(area);
    return ok;
}

bool ism_sheet_assemble(const ism_sheet_tris *t, double min_area, ism_mesh *mesh,
                        ism_locus *io)
{
    size_t nt = t->ntris, nx = t->xmap.n;
    uint32_t *comp = malloc((nt ? nt : 1) * sizeof *comp);
    uint32_t *vertex_of = malloc((nx ? nx : 1) * sizeof *vertex_of);
    size_t *order = malloc((nt ? nt : 1) * sizeof *order);
    size_t ncomp = comp ? label_components(t, comp) : SIZE_MAX;
    size_t *start = ncomp != SIZE_MAX ? calloc(ncomp + 1, sizeof *start) : NULL;
    uint8_t *drop = ncomp != SIZE_MAX ? malloc(ncomp + 1) : NULL;
    bool ok = comp && vertex_of && order && start && drop
           && find_scraps(t, comp, ncomp, min_area, drop)
           && ism_mesh_reserve(mesh, mesh->nverts + nx, mesh->ntris + nt);
    if (ok) {
        for (size_t i = 0; i < nx; i++)
            vertex_of[i] = UINT32_MAX;
        for (size_t i = 0; i < nt; i++) /* counting sort by component, stable */
            start[comp[i] + 1]++;
        for (size_t c = 0; c < ncomp; c++)
            start[c + 1] += start[c];
        size_t *fill = start; /* start[c] moves to the end of component c, then is rebuilt */
        for (size_t i = 0; i < nt; i++)
            order[fill[comp[i]]++] = i;
        for (size_t c = ncomp; c > 0; c--)
            start[c] = start[c - 1];
        start[0] = 0;
    }
    for (size_t c = 0; ok && c < ncomp; c++) {
        if (drop[c])
            continue;
        ism_double_sheet s = {mesh->ntris, start[c + 1] - start[c], 0};
        s.area = append_component(t, order, start[c], start[c + 1], vertex_of, mesh);
        ok = s.area >= 0 && ism_locus_add_sheet(io, &s);
    }
    free(comp);
    free(vertex_of);
    free(order);
    free(start);
    free(drop);
    return ok;
}
