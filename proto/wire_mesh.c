/* wire_mesh.c — converts the polygoniser's mesh (double positions, normals from ∇f that may
 * be zero at singular points) and the analysis's per-vertex figures into the arrays the
 * encoders send. A zero normal would decode as an arbitrary direction (Draco's octahedral
 * coder) or render black, so it is replaced by the area-weighted normal of the triangles
 * around the vertex (and +z when even that vanishes). Corners get normals of their own where
 * one vertex normal cannot serve every triangle round it: a crease's sides (the branch
 * normals) and the sheets through a vertex on the singular locus (ism_wire_corner_normals). */
#include "proto/wire_mesh.h"
#include "proto/request.h"
#include "proto/sheet_groups.h"
#include "core/curves/branches.h"
#include "core/curves/crease_normals.h"
#include "core/eval/eval.h"
#include "core/util/grow.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static bool is_zero3(const float *v) { return v[0] == 0 && v[1] == 0 && v[2] == 0; }

/* Triangle t's normal as it is wound, twice its area long. */
static void face_cross(const ism_mesh *m, size_t t, double cr[3])
{
    const uint32_t *v = m->tri + 3 * t;
    ism_tri_cross3(m->pos + 3 * v[0], m->pos + 3 * v[1], m->pos + 3 * v[2], cr);
}

static void fill_missing_normals(const ism_mesh *m, float *normal)
{
    size_t missing = 0;
    for (size_t i = 0; i < m->nverts; i++) {
        float *n = normal + 3 * i;
        if (!isfinite(n[0]) || !isfinite(n[1]) || !isfinite(n[2]))
            n[0] = n[1] = n[2] = 0;
        missing += is_zero3(n);
    }
    if (!missing)
        return;
    double *acc = calloc(m->nverts * 3, sizeof *acc);
    if (acc) {
        for (size_t t = 0; t < m->ntris; t++) {
            const uint32_t *v = m->tri + 3 * t;
            double cr[3];
            face_cross(m, t, cr);
            for (int k = 0; k < 3; k++)
                if (is_zero3(normal + 3 * v[k]))
                    for (int j = 0; j < 3; j++)
                        acc[3 * v[k] + j] += cr[j]; /* |cross| = 2 area: area weighting */
        }
    }
    for (size_t i = 0; i < m->nverts; i++) {
        float *n = normal + 3 * i;
        if (!is_zero3(n))
            continue;
        double *s = acc ? acc + 3 * i : NULL;
        double len = s ? sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]) : 0;
        if (len > 0 && isfinite(len))
            for (int k = 0; k < 3; k++)
                n[k] = (float)(s[k] / len);
        else
            n[2] = 1;
    }
    free(acc);
}

static float *clamped_copy(const float *src, size_t n, double limit)
{
    float *d = malloc((n ? n : 1) * sizeof *d);
    if (!d)
        return NULL;
    for (size_t i = 0; i < n; i++) {
        double v = isfinite(src[i]) ? src[i] : 0;
        if (limit > 0)
            v = v > limit ? limit : v < -limit ? -limit : v;
        d[i] = (float)v;
    }
    return d;
}

bool ism_wire_mesh_build(const ism_mesh *m, const ism_analysis *a, unsigned attrs,
                         double curvature_limit, ism_wire_mesh *w)
{
    memset(w, 0, sizeof *w);
    w->nverts = m->nverts;
    w->ntris = m->ntris;
    w->tri = m->tri;
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *v = m->tri + 3 * t;
        w->live_triangles += v[0] != v[1] && v[1] != v[2] && v[0] != v[2];
    }
    w->pos = malloc((m->nverts ? m->nverts : 1) * 3 * sizeof *w->pos);
    if (!w->pos)
        goto fail;
    for (int k = 0; k < 3; k++) {
        w->bounds[k] = INFINITY;
        w->bounds[k + 3] = -INFINITY;
    }
    for (size_t i = 0; i < 3 * m->nverts; i++) {
        float f = (float)m->pos[i];
        w->pos[i] = f;
        int k = (int)(i % 3);
        w->bounds[k] = fmin(w->bounds[k], f);
        w->bounds[k + 3] = fmax(w->bounds[k + 3], f);
    }
    if (!m->nverts)
        memset(w->bounds, 0, sizeof w->bounds);
    if (attrs & ISM_ATTR_NORMAL) {
        w->normal = malloc((m->nverts ? m->nverts : 1) * 3 * sizeof *w->normal);
        if (!w->normal)
            goto fail;
        if (m->normal && m->nverts)
            memcpy(w->normal, m->normal, m->nverts * 3 * sizeof *w->normal);
        else
            memset(w->normal, 0, m->nverts * 3 * sizeof *w->normal);
        fill_missing_normals(m, w->normal);
    }
    if (a && (attrs & ISM_ATTR_MEAN_CURVATURE) && a->mean_curvature &&
        !(w->mean_curvature = clamped_copy(a->mean_curvature, m->nverts, curvature_limit)))
        goto fail;
    if (a && (attrs & ISM_ATTR_GAUSS_CURVATURE) && a->gauss_curvature &&
        !(w->gauss_curvature = clamped_copy(a->gauss_curvature, m->nverts,
                                            curvature_limit > 0
                                                ? curvature_limit * curvature_limit
                                                : 0)))
        goto fail;
    if (a && (attrs & ISM_ATTR_CLASS))
        w->vertex_class = a->vertex_class;
    return true;
fail:
    ism_wire_mesh_free(w);
    return false;
}

void ism_wire_mesh_free(ism_wire_mesh *w)
{
    free(w->pos);
    free(w->normal);
    free(w->mean_curvature);
    free(w->gauss_curvature);
    memset(w, 0, sizeof *w);
}

/* Whether corner normal c (unit, or zero when no branch gave one) is the vertex's v to
 * ISM_CORNER_NORMAL_MIN_ANGLE. */
static bool same_normal(const float *c, const float *v)
{
    double d = (double)c[0] * v[0] + (double)c[1] * v[1] + (double)c[2] * v[2];
    return is_zero3(c) || d >= cos(ISM_CORNER_NORMAL_MIN_ANGLE);
}

/* A vertex is on the singular locus (a double curve, a pinch or triple point: ∇f = 0, the
 * vertex normal there is noise or the fill's average of every sheet through it, which may lie
 * along the curve) when |∇f| there is below SINGULAR_GRAD_REL × the largest |∇f| at the other
 * corners of a triangle it is in: next to a double curve |∇f| grows linearly with the distance
 * r, so a corner a cell away has |∇f| ~ |H| r, while on the curve it is rounding (Steiner:
 * ~1e-16 against ~1e-2); 1e-6 leaves eight decades between the two. */
#define SINGULAR_GRAD_REL 1e-6
/* A sheet normal (∇f at the triangle's corners off the locus) stands for the triangle's own
 * plane only within this angle of its normal line: sheet_groups.h leaves 10° for it (the
 * chord against the tangent plane, below that on Steiner's curves at the default bound).
 * Beside a pinch point the umbrella's tangent plane turns through 90° within a cell, and a
 * triangle's other corner may lie on the fold, where ∇f points along the curve: its sheet
 * normal lay in the face itself (Steiner at 1e-3 × the diagonal: 48 corners within a cell
 * of the six pinch points more than 30° off their face, up to 90°). Past the angle the
 * corner takes its face's normal, wound as the mesh is (with ∇f). */
#define SHEET_FACE_MAX_ANGLE (10.0 * 3.14159265358979323846 / 180.0)

/* Per vertex of m: |∇f| (NULL when out of memory). */
static double *gradient_norms(const ism_tape *f, ism_eval_ws *ws, const ism_mesh *m)
{
    double *g = malloc((m->nverts ? m->nverts : 1) * sizeof *g);
    for (size_t v = 0; g && v < m->nverts; v++) {
        const double *p = m->pos + 3 * v;
        double d[3];
        ism_eval_gradient(f, ws, p[0], p[1], p[2], d);
        double n = ism_norm3(d);
        g[v] = isfinite(n) ? n : 0;
    }
    return g;
}

/* The corners of triangle t at vertices on the singular locus whose normal in cn is still
 * their vertex's (no crease side claimed them) get their own sheet's normal: the sum of the
 * triangle's other corners' normals (∇f on the same half-sheet, so the mesh's sign), or ∇f
 * at the centroid when every corner is on the locus; marked in on_locus (per corner). */
static void singular_corners(const ism_tape *f, ism_eval_ws *ws, const ism_mesh *m,
                             const float *vn, const double *gn, size_t t, float *cn,
                             uint8_t *on_locus)
{
    const uint32_t *tv = m->tri + 3 * t;
    double top = fmax(gn[tv[0]], fmax(gn[tv[1]], gn[tv[2]]));
    bool on[3];
    double s[3] = {0, 0, 0};
    int off = 0;
    for (int i = 0; i < 3; i++) {
        on[i] = gn[tv[i]] <= SINGULAR_GRAD_REL * top;
        if (!on[i]) {
            off++;
            for (int k = 0; k < 3; k++)
                s[k] += cn[9 * t + 3 * i + k];
        }
    }
    if (off == 3 || !(top > 0))
        return;
    if (!off) {
        double c[3] = {0, 0, 0};
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++)
                c[k] += m->pos[3 * (size_t)tv[i] + k] / 3;
        ism_eval_gradient(f, ws, c[0], c[1], c[2], s);
    }
    double n = ism_norm3(s);
    if (!(n > 0) || !isfinite(n))
        return;
    double face[3];
    face_cross(m, t, face);
    double fl = ism_norm3(face);
    if (fl > 0 && isfinite(fl) && fabs(ism_dot3(face, s)) < cos(SHEET_FACE_MAX_ANGLE) * fl * n) {
        for (int k = 0; k < 3; k++)
            s[k] = face[k];
        n = fl;
    }
    for (int i = 0; i < 3; i++) {
        float *c = cn + 9 * t + 3 * i;
        if (!on[i] || !same_normal(c, vn + 3 * (size_t)tv[i]))
            continue; /* off the locus, or a crease side's: kept */
        for (int k = 0; k < 3; k++)
            c[k] = (float)(s[k] / n);
        on_locus[3 * t + i] = 1;
    }
}

/* cn: per corner, its crease side's normal (f with min/max) or its vertex's; then the locus
 * corners' sheet normals, marked in *on_locus (calloc'd per corner). False when out of
 * memory. */
static bool all_corner_normals(const ism_tape *f, const ism_mesh *m, const ism_cut *cut,
                               const float *vn, float *cn, uint8_t **on_locus)
{
    ism_eval_ws *ws = ism_eval_ws_new(f);
    double *gn = ws ? gradient_norms(f, ws, m) : NULL;
    *on_locus = gn ? calloc(3 * m->ntris, 1) : NULL;
    bool ok = *on_locus != NULL;
    if (ok && ism_branches_any(f))
        ok = ism_crease_corner_normals(f, m, cut, cn);
    else if (ok)
        for (size_t c = 0; c < 3 * m->ntris; c++)
            memcpy(cn + 3 * c, vn + 3 * (size_t)m->tri[c], 3 * sizeof *cn);
    for (size_t t = 0; ok && t < m->ntris; t++)
        singular_corners(f, ws, m, vn, gn, t, cn, *on_locus);
    if (ok)
        ok = ism_sheet_groups_join(m, *on_locus, cn); /* one normal per half-sheet */
    free(gn);
    ism_eval_ws_free(ws);
    return ok;
}

bool ism_wire_corner_normals(const ism_tape *f, const ism_analysis *an, const ism_mesh *m,
                             const ism_cut *cut, const ism_wire_mesh *w, size_t *n,
                             uint32_t **at, float **normal, uint8_t **locus)
{
    *n = 0;
    *at = NULL;
    *normal = NULL;
    *locus = NULL;
    /* no crease sides, and the analysis (|∇f| at every vertex, on the job's threads) found
     * no vertex where ∇f vanishes: every corner keeps its vertex's normal, so none to look
     * for (without an analysis, in a preview, |∇f| is evaluated here) */
    if (!w->normal || !m->ntris || (an && !an->singular_vertices && !ism_branches_any(f)))
        return true;
    if (m->ntris > UINT32_MAX / 3)
        return false; /* corner indices are uint32 */
    float *cn = malloc(m->ntris * 9 * sizeof *cn);
    uint8_t *on = NULL;
    if (!cn || !all_corner_normals(f, m, cut, w->normal, cn, &on)) {
        free(cn);
        free(on);
        return false;
    }
    size_t k = 0, cap = 0;
    bool any_locus = false;
    for (size_t c = 0; c < 3 * m->ntris; c++) {
        if (same_normal(cn + 3 * c, w->normal + 3 * (size_t)m->tri[c]))
            continue;
        if (!ism_grow((void **)at, &cap, k + 1, sizeof **at, 64)) {
            free(cn);
            free(on);
            free(*at);
            *at = NULL;
            return false;
        }
        memmove(cn + 3 * k, cn + 3 * c, 3 * sizeof *cn); /* compacted in place: k <= c */
        on[k] = on[c];                                   /* likewise */
        any_locus |= on[k];
        (*at)[k++] = (uint32_t)c;
    }
    if (!k) {
        free(cn);
        free(on);
        return true;
    }
    float *shrunk = realloc(cn, k * 3 * sizeof *cn);
    *normal = shrunk ? shrunk : cn;
    if (any_locus) {
        uint8_t *o = realloc(on, k);
        *locus = o ? o : on;
    } else {
        free(on);
    }
    *n = k;
    return true;
}
