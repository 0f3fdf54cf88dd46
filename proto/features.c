/* features.c — gathers the non-manifold curves and points from the analysis and the boundary
 * chains from the mesh into one structure, and writes the features JSON the viewer draws
 * beside a Draco mesh (format in features.h). */
#include "proto/features.h"
#include "proto/json_writer.h"
#include "proto/polyline_thin.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const class_names[] = {"manifold", "boundary", "nonmanifold_edge",
                                          "nonmanifold_point", "isolated"};

const char *ism_point_kind_name(int kind)
{
    switch (kind) {
    case ISM_POINT_CONES: return "cones";
    case ISM_POINT_CURVE_END: return "curve_end";
    case ISM_POINT_JUNCTION: return "junction";
    default: return "unknown";
    }
}

void ism_polylines_free(ism_polylines *p)
{
    free(p->start);
    free(p->verts);
    memset(p, 0, sizeof *p);
}

/* A copy of n polylines given as start (n + 1 entries, NULL when n is 0) and verts. */
static bool copy_polylines(size_t n, const uint32_t *start, const uint32_t *verts,
                           ism_polylines *c)
{
    size_t nv = n ? start[n] : 0;
    c->start = malloc((n + 1) * sizeof *c->start);
    c->verts = malloc((nv ? nv : 1) * sizeof *c->verts);
    if (!c->start || !c->verts)
        return false;
    c->n = n;
    if (n)
        memcpy(c->start, start, (n + 1) * sizeof *c->start);
    else
        c->start[0] = 0;
    if (nv)
        memcpy(c->verts, verts, nv * sizeof *c->verts);
    return true;
}

bool ism_features_build(const ism_analysis *a, ism_features *f)
{
    memset(f, 0, sizeof *f);
    if (a) {
        if (!copy_polylines(a->ncurves, a->curve_start, a->curve_verts, &f->curves) ||
            !copy_polylines(a->nboundaries, a->boundary_start, a->boundary_verts,
                            &f->boundaries))
            goto fail;
        size_t np = a->npoints;
        f->points = malloc((np ? np : 1) * sizeof *f->points);
        f->point_kind = malloc(np ? np : 1);
        f->point_class = malloc(np ? np : 1);
        if (!f->points || !f->point_kind || !f->point_class)
            goto fail;
        f->npoints = np;
        for (size_t i = 0; i < np; i++) {
            f->points[i] = a->points[i];
            f->point_kind[i] = a->point_kind ? a->point_kind[i] : ISM_POINT_CONES;
            f->point_class[i] = a->vertex_class ? a->vertex_class[a->points[i]] : 0;
        }
    } else if (!copy_polylines(0, NULL, NULL, &f->curves) ||
               !copy_polylines(0, NULL, NULL, &f->boundaries)) {
        goto fail;
    }
    return true;
fail:
    ism_features_free(f);
    return false;
}

void ism_features_free(ism_features *f)
{
    ism_polylines_free(&f->curves);
    ism_polylines_free(&f->boundaries);
    ism_polylines_free(&f->arcs);
    free(f->arc_kind);
    free(f->arc_curve);
    free(f->points);
    free(f->point_kind);
    free(f->point_class);
    memset(f, 0, sizeof *f);
}

void ism_features_chain_xyz(ism_jw *w, const ism_mesh *m, const uint32_t *verts, size_t n,
                            double tol, int d, bool full_doubles)
{
    uint8_t *keep = NULL;
    if (tol > 0 && d >= 0 && n > 2) {
        keep = malloc(n);
        if (!keep || !ism_polyline_thin(m->pos, verts, n, tol - ISM_FEATURES_ROUNDING(d), keep)) {
            free(keep);
            w->failed = true; /* out of memory: the text is unusable */
            return;
        }
    }
    ism_jw_array(w);
    for (size_t i = 0; i < n; i++) {
        if (keep && !keep[i])
            continue;
        const double *p = m->pos + 3 * (size_t)verts[i];
        for (int k = 0; k < 3; k++)
            if (d >= 0)
                ism_jw_number_decimals(w, p[k], d);
            else if (full_doubles)
                ism_jw_number(w, p[k]);
            else
                ism_jw_float(w, (float)p[k]);
    }
    ism_jw_array_end(w);
    free(keep);
}

/* Polylines of mesh vertices; on (may be NULL) gives each line's "on_locus" and vert_on (per
 * polyline vertex) its "off_edges": the edges with an end off the locus, the ones the check
 * counts. Positions with d decimals (d < 0: float32); thinned within tol (> 0; the digits
 * table in features.h): every chain when on is NULL (boundaries), else a chain with every
 * edge on the locus. Returns edges. */
static size_t write_lines(ism_jw *w, const ism_mesh *m, const ism_polylines *p,
                          const uint8_t *on, const uint8_t *vert_on, double tol, int d)
{
    size_t edges = 0;
    ism_jw_array(w);
    for (size_t i = 0; i < p->n; i++) {
        uint32_t s = p->start[i], e = p->start[i + 1];
        ism_jw_object(w);
        ism_jw_key(w, "closed");
        ism_jw_bool(w, e - s > 1 && p->verts[s] == p->verts[e - 1]);
        bool thin = true;
        if (on) {
            ism_jw_key(w, "on_locus");
            ism_jw_bool(w, on[i]);
            ism_jw_key(w, "off_edges");
            ism_jw_array(w);
            for (uint32_t j = s; j + 1 < e; j++)
                if (!(vert_on[j] && vert_on[j + 1])) {
                    ism_jw_uint(w, j - s);
                    thin = false; /* off_edges index every vertex */
                }
            ism_jw_array_end(w);
            thin = thin && on[i];
        }
        ism_jw_key(w, "xyz");
        ism_features_chain_xyz(w, m, p->verts + s, e - s, thin ? tol : 0, d, false);
        ism_jw_object_end(w);
        edges += e > s ? e - s - 1 : 0;
    }
    ism_jw_array_end(w);
    return edges;
}

static void write_singular_point(ism_jw *w, const ism_sing_point *p, int cones)
{
    ism_jw_object(w);
    ism_jw_key(w, "xyz");
    ism_jw_numbers(w, p->p, 3);
    ism_jw_key(w, "radius");
    ism_jw_number(w, p->radius);
    ism_jw_key(w, "type");
    ism_jw_string(w, ism_sing_type_name(p->type));
    ism_jw_key(w, "certified");
    ism_jw_bool(w, p->certified);
    ism_jw_key(w, "certificate");
    ism_jw_string(w, ism_cert_kind_name(p->certificate));
    if (p->certificate >= ISM_CERT_DEFLATION) {
        ism_jw_key(w, "perturbation");
        ism_jw_number(w, p->perturbation);
    }
    if (ism_uncert_why_name(p->uncertified_why)) {
        ism_jw_key(w, "uncertified_reason");
        ism_jw_string(w, ism_uncert_why_name(p->uncertified_why));
    }
    if (p->exists_radius > 0.0) {
        ism_jw_key(w, "exists_within");
        ism_jw_number(w, p->exists_radius);
    }
    ism_jw_key(w, "hessian_eigenvalues");
    ism_jw_numbers(w, p->eig, 3);
    ism_jw_key(w, "residual_f");
    ism_jw_number(w, p->residual_f);
    ism_jw_key(w, "residual_grad");
    ism_jw_number(w, p->residual_grad);
    ism_jw_key(w, "cones");
    ism_jw_int(w, cones);
    ism_jw_object_end(w);
}

int ism_features_decimals(double tol)
{
    if (!isfinite(tol) || !(tol > 0))
        return -1;
    for (int d = 0; d <= ISM_FEATURES_MAX_DECIMALS; d++)
        if (ISM_FEATURES_ROUNDING(d) <= tol)
            return d;
    return -1; /* finer than a double near 1 prints: in full */
}

static void write_curve_end(ism_jw *w, const ism_sing_curve *c, int e, const ism_locus *l,
                            int d)
{
    size_t at = e == 0 ? 0 : c->n - 1;
    ism_jw_object(w);
    ism_jw_key(w, "type");
    ism_jw_string(w, ism_end_type_name(c->end_type[e]));
    ism_jw_key(w, "xyz");
    ism_jw_numbers_decimals(w, c->xyz + 3 * at, 3, d);
    ism_jw_key(w, "point");
    if (c->end_point[e] >= 0 && (size_t)c->end_point[e] < l->npoints)
        ism_jw_int(w, c->end_point[e]);
    else
        ism_jw_null(w);
    ism_jw_object_end(w);
}

/* The trace points of c to print (keep, c->n bytes): every one when tol is 0, else those
 * ism_polyline_thin keeps within tol on either side of the first uncertified point (kept, so
 * that its index can be given). False when out of memory. */
static bool curve_keep(const ism_sing_curve *c, double tol, uint8_t *keep)
{
    if (!(tol > 0) || c->n <= 2) {
        memset(keep, 1, c->n);
        return true;
    }
    size_t cut = c->first_uncertified >= 0 && (size_t)c->first_uncertified < c->n
                     ? (size_t)c->first_uncertified
                     : 0;
    return ism_polyline_thin(c->xyz, NULL, cut + 1, tol, keep) &&
           ism_polyline_thin(c->xyz + 3 * cut, NULL, c->n - cut, tol, keep + cut);
}

/* A singular curve: its points with its certificate's decimals, thinned within draw_tol
 * (> 0; the table in features.h). */
static void write_singular_curve(ism_jw *w, const ism_sing_curve *c, const ism_locus *l,
                                 double draw_tol)
{
    int d = ism_features_decimals(c->cert_radius); /* the table in features.h */
    double tol = draw_tol > 0 ? draw_tol - (d < 0 ? 0 : ISM_FEATURES_ROUNDING(d)) : 0;
    uint8_t *keep = malloc(c->n ? c->n : 1);
    if (!keep || !curve_keep(c, tol, keep)) {
        free(keep);
        w->failed = true; /* out of memory: the text is unusable */
        return;
    }
    long printed_uncertified = -1; /* the first uncertified point's place among the printed */
    ism_jw_object(w);
    ism_jw_key(w, "kind");
    ism_jw_string(w, ism_curve_kind_name(c->kind));
    ism_jw_key(w, "closed");
    ism_jw_bool(w, c->closed);
    ism_jw_key(w, "points");
    ism_jw_uint(w, c->n);
    if (tol > 0) {
        ism_jw_key(w, "tolerance");
        ism_jw_number(w, draw_tol);
    }
    ism_jw_key(w, "xyz");
    ism_jw_array(w);
    for (size_t i = 0, at = 0; i < c->n; i++) {
        if (!keep[i])
            continue;
        if ((long)i == c->first_uncertified)
            printed_uncertified = (long)at;
        at++;
        for (int k = 0; k < 3; k++)
            ism_jw_number_decimals(w, c->xyz[3 * i + k], d);
    }
    ism_jw_array_end(w);
    free(keep);
    ism_jw_key(w, "ends");
    ism_jw_array(w);
    for (int e = 0; e < 2 && !c->closed && c->n; e++)
        write_curve_end(w, c, e, l, d);
    ism_jw_array_end(w);
    ism_jw_key(w, "certified");
    ism_jw_bool(w, c->certified);
    ism_jw_key(w, "uncertified_points");
    ism_jw_uint(w, c->uncertified_points);
    ism_jw_key(w, "certificate_radius");
    ism_jw_number(w, d < 0 ? c->cert_radius : c->cert_radius + ISM_FEATURES_ROUNDING(d));
    ism_jw_key(w, "first_uncertified");
    if (c->uncertified_points && printed_uncertified >= 0) {
        ism_jw_object(w);
        ism_jw_key(w, "index");
        ism_jw_int(w, printed_uncertified);
        ism_jw_key(w, "xyz");
        ism_jw_numbers_decimals(w, c->xyz + 3 * (size_t)c->first_uncertified, 3, d);
        ism_jw_key(w, "residual_f");
        ism_jw_number(w, c->first_residual_f);
        ism_jw_key(w, "residual_grad");
        ism_jw_number(w, c->first_residual_grad);
        ism_jw_object_end(w);
    } else {
        ism_jw_null(w);
    }
    ism_jw_object_end(w);
}

/* The locus's counts: points by type and certification, curves by kind, sheets. */
void ism_locus_counts_json(ism_jw *w, const ism_locus *l)
{
    size_t by_type[ISM_SING_TYPES] = {0}, certified = 0, by_kind[ISM_CURVE_KINDS] = {0};
    size_t curves_certified = 0;
    for (size_t i = 0; l && i < l->npoints; i++) {
        if (l->points[i].type >= 0 && l->points[i].type < ISM_SING_TYPES)
            by_type[l->points[i].type]++;
        certified += l->points[i].certified;
    }
    for (size_t i = 0; l && i < l->ncurves; i++) {
        if (l->curves[i].kind >= 0 && l->curves[i].kind < ISM_CURVE_KINDS)
            by_kind[l->curves[i].kind]++;
        curves_certified += l->curves[i].certified;
    }
    ism_jw_key(w, "singular_points");
    ism_jw_uint(w, l ? l->npoints : 0);
    ism_jw_key(w, "certified");
    ism_jw_uint(w, certified);
    ism_jw_key(w, "uncertified");
    ism_jw_uint(w, (l ? l->npoints : 0) - certified);
    ism_jw_key(w, "by_type");
    ism_jw_object(w);
    for (int t = 0; t < ISM_SING_TYPES; t++) {
        ism_jw_key(w, ism_sing_type_name(t));
        ism_jw_uint(w, by_type[t]);
    }
    ism_jw_object_end(w);
    ism_jw_key(w, "curves");
    ism_jw_uint(w, l ? l->ncurves : 0);
    for (int k = 0; k < ISM_CURVE_KINDS; k++) {
        char key[32];
        snprintf(key, sizeof key, "%s_curves", ism_curve_kind_name(k));
        ism_jw_key(w, key);
        ism_jw_uint(w, by_kind[k]);
    }
    ism_jw_key(w, "certified_curves");
    ism_jw_uint(w, curves_certified);
    ism_jw_key(w, "uncertified_curves");
    ism_jw_uint(w, (l ? l->ncurves : 0) - curves_certified);
    ism_jw_key(w, "double_sheets");
    ism_jw_uint(w, l ? l->nsheets : 0);
}

static void write_locus(ism_jw *w, const ism_mesh *m, const ism_features *f, double tol, int d)
{
    const ism_locus *l = f->locus;
    ism_jw_key(w, "singular_points");
    ism_jw_array(w);
    for (size_t i = 0; l && i < l->npoints; i++) {
        int cones = f->check ? f->check->point_cones[i] : l->points[i].cones;
        write_singular_point(w, &l->points[i], cones);
    }
    ism_jw_array_end(w);
    ism_jw_key(w, "curves");
    ism_jw_array(w);
    for (size_t i = 0; l && i < l->ncurves; i++)
        write_singular_curve(w, &l->curves[i], l, f->draw_tol);
    ism_features_cut_curves_json(w, m, f->arrangement, f->cut_fns, tol, d);
    ism_jw_array_end(w);
    ism_jw_key(w, "double_sheets");
    ism_jw_array(w);
    for (size_t i = 0; l && i < l->nsheets; i++) {
        ism_jw_object(w);
        ism_jw_key(w, "first_triangle");
        ism_jw_uint(w, l->sheets[i].first_triangle);
        ism_jw_key(w, "triangles");
        ism_jw_uint(w, l->sheets[i].triangles);
        ism_jw_key(w, "area");
        ism_jw_number(w, l->sheets[i].area);
        ism_jw_object_end(w);
    }
    ism_jw_array_end(w);
}

static void write_mesh_points(ism_jw *w, const ism_mesh *m, const ism_features *f, int d)
{
    ism_jw_array(w);
    for (size_t i = 0; i < f->npoints; i++) {
        ism_jw_object(w);
        ism_jw_key(w, "xyz");
        ism_features_chain_xyz(w, m, f->points + i, 1, 0, d, false);
        ism_jw_key(w, "class");
        ism_jw_int(w, f->point_class[i]);
        ism_jw_key(w, "kind");
        ism_jw_string(w, ism_point_kind_name(f->point_kind[i]));
        if (f->check) {
            ism_jw_key(w, "on_locus");
            ism_jw_bool(w, f->check->point_on[i]);
        }
        ism_jw_object_end(w);
    }
    ism_jw_array_end(w);
}

char *ism_features_json(const ism_mesh *m, const ism_features *f, size_t *len)
{
    ism_jw w;
    ism_jw_init(&w);
    ism_jw_object(&w);
    ism_jw_key(&w, "version");
    ism_jw_int(&w, ISM_FEATURES_VERSION);
    ism_jw_key(&w, "classes");
    ism_jw_array(&w);
    for (size_t i = 0; i < sizeof class_names / sizeof class_names[0]; i++)
        ism_jw_string(&w, class_names[i]);
    ism_jw_array_end(&w);
    /* the table in features.h: mesh positions within half the drawing tolerance */
    int d = ism_features_decimals(0.5 * f->draw_tol);
    double tol = d >= 0 ? f->draw_tol : 0;
    write_locus(&w, m, f, tol, d);
    ism_jw_key(&w, "nonmanifold_edges");
    const ism_locus_check *chk = f->check;
    bool check_fits = chk && chk->curve_on && chk->curve_vert_on && chk->point_on;
    size_t curve_edges = write_lines(&w, m, &f->curves, check_fits ? chk->curve_on : NULL,
                                     check_fits ? chk->curve_vert_on : NULL, tol, d);
    ism_jw_key(&w, "nonmanifold_points");
    write_mesh_points(&w, m, f, d);
    ism_jw_key(&w, "boundaries");
    size_t boundary_edges = write_lines(&w, m, &f->boundaries, NULL, NULL, tol, d);
    if (f->arrangement) {
        ism_jw_key(&w, "arrangement");
        ism_features_arrangement_json(&w, m, f->arrangement);
    }
    if (tol > 0) {
        ism_jw_key(&w, "tolerance");
        ism_jw_number(&w, tol);
    }
    bool incomplete = f->locus && f->locus->incomplete;
    ism_jw_key(&w, "incomplete");
    ism_jw_bool(&w, incomplete);
    if (incomplete) {
        ism_jw_key(&w, "incomplete_why");
        ism_jw_string(&w, f->locus->incomplete_why);
    }
    ism_jw_key(&w, "counts");
    ism_jw_object(&w);
    ism_locus_counts_json(&w, f->locus);
    ism_jw_key(&w, "nonmanifold_chains");
    ism_jw_uint(&w, f->curves.n);
    ism_jw_key(&w, "nonmanifold_edges");
    ism_jw_uint(&w, curve_edges);
    ism_jw_key(&w, "nonmanifold_points");
    ism_jw_uint(&w, f->npoints);
    ism_jw_key(&w, "artefacts");
    if (chk)
        ism_jw_uint(&w, chk->artefacts);
    else
        ism_jw_null(&w);
    ism_jw_key(&w, "boundaries");
    ism_jw_uint(&w, f->boundaries.n);
    ism_jw_key(&w, "boundary_edges");
    ism_jw_uint(&w, boundary_edges);
    ism_jw_object_end(&w);
    ism_jw_object_end(&w);
    return ism_jw_take(&w, len);
}
