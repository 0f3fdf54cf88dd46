/* sheet_groups.c — the half-sheet join of sheet_groups.h: the marked corners listed per
 * vertex, then at each vertex the sets joined over the fan edges its triangles share off the
 * locus (a vertex has at most a few hundred corners: a node's fans); a set one normal serves
 * is joined whole, any other by a small agglomeration that keeps each join only while the
 * joined normal serves every member. */
#include "proto/sheet_groups.h"
#include "core/analysis/unionfind.h"
#include "core/util/vec3.h"

#include <math.h>
#include <stdlib.h>

/* Member i's triangle has the mesh edge (v, w), w off the locus. */
typedef struct fan_link {
    uint32_t w, i;
} fan_link;

/* Members a and b share such an edge; dot of their normals (closest first). */
typedef struct fan_pair {
    double dot;
    uint32_t a, b;
} fan_pair;

static int cmp_link(const void *x, const void *y)
{
    const fan_link *p = x, *q = y;
    if (p->w != q->w)
        return p->w < q->w ? -1 : 1;
    return (p->i > q->i) - (p->i < q->i);
}

static int cmp_pair(const void *x, const void *y)
{
    const fan_pair *p = x, *q = y;
    if (p->dot != q->dot)
        return p->dot > q->dot ? -1 : 1;
    if (p->a != q->a)
        return p->a < q->a ? -1 : 1;
    return (p->b > q->b) - (p->b < q->b);
}

static double dot3f(const float *a, const float *b)
{
    return (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2];
}

/* Scratch for one vertex of at most cap members. */
typedef struct fan_ws {
    fan_link *link;  /* 2 per member */
    fan_pair *pair;  /* 1 per member (each link run of two gives one) */
    uint32_t *parent, *size;
    double *sum;     /* 3 per member: the set's sum of normals at its root */
    uint8_t *whole;  /* per member: its half-sheet is joined whole */
} fan_ws;

static bool fan_ws_alloc(fan_ws *s, size_t cap)
{
    s->link = malloc(2 * cap * sizeof *s->link);
    s->pair = malloc(cap * sizeof *s->pair);
    s->parent = malloc(cap * sizeof *s->parent);
    s->size = malloc(cap * sizeof *s->size);
    s->sum = malloc(3 * cap * sizeof *s->sum);
    s->whole = malloc(cap);
    return s->link && s->pair && s->parent && s->size && s->sum && s->whole;
}

static void fan_ws_free(fan_ws *s)
{
    free(s->link);
    free(s->pair);
    free(s->parent);
    free(s->size);
    free(s->sum);
    free(s->whole);
}

/* Member i its own set, its own normal the set's sum. */
static void singleton(fan_ws *s, uint32_t i, const uint32_t *corner, const float *cn)
{
    s->parent[i] = i;
    s->size[i] = 1;
    for (int d = 0; d < 3; d++)
        s->sum[3 * i + d] = cn[3 * (size_t)corner[i] + d];
}

/* Joins the sets of a and b: the smaller root keeps the size and sum (unionfind.h). */
static void join_sets(fan_ws *s, uint32_t ra, uint32_t rb)
{
    ism_an_uf_union(s->parent, ra, rb);
    uint32_t r = ra < rb ? ra : rb;
    s->size[r] = s->size[ra] + s->size[rb];
    for (int d = 0; d < 3; d++) /* r is ra or rb: each d reads both before it writes */
        s->sum[3 * r + d] = s->sum[3 * ra + d] + s->sum[3 * rb + d];
}

/* Whether every member of the sets ra and rb is within cmin (a cosine) of the unit u. */
static bool serves_all(const fan_ws *s, const uint32_t *corner, uint32_t k, uint32_t ra,
                       uint32_t rb, const double *u, const float *cn, double cmin)
{
    for (uint32_t i = 0; i < k; i++) {
        uint32_t r = ism_an_uf_find(s->parent, i);
        if (r != ra && r != rb)
            continue;
        const float *n = cn + 3 * (size_t)corner[i];
        if ((double)n[0] * u[0] + (double)n[1] * u[1] + (double)n[2] * u[2] < cmin)
            return false;
    }
    return true;
}

/* The pairs of members whose triangles share an edge (v, w), w unmarked, of exactly two of
 * them (within one sheet: an edge along the locus has four, or a marked end), closest
 * normals first; their number. */
static size_t fan_pairs(const ism_mesh *m, uint32_t v, const uint32_t *corner, uint32_t k,
                        const size_t *start, const float *cn, fan_ws *s)
{
    size_t nl = 0, np = 0;
    for (uint32_t i = 0; i < k; i++) {
        const uint32_t *t = m->tri + 3 * (size_t)(corner[i] / 3);
        for (int j = 0; j < 3; j++)
            if (t[j] != v && start[t[j] + 1] == start[t[j]])
                s->link[nl++] = (fan_link){t[j], i};
    }
    qsort(s->link, nl, sizeof *s->link, cmp_link);
    for (size_t a = 0, e; a < nl; a = e) {
        for (e = a + 1; e < nl && s->link[e].w == s->link[a].w; e++)
            ;
        uint32_t x = s->link[a].i, y = s->link[a + 1 < e ? a + 1 : a].i;
        if (e - a == 2 && x != y)
            s->pair[np++] = (fan_pair){dot3f(cn + 3 * (size_t)corner[x],
                                             cn + 3 * (size_t)corner[y]), x, y};
    }
    qsort(s->pair, np, sizeof *s->pair, cmp_pair);
    return np;
}

/* The half-sheets (sets joined over every pair): whole[i] when member i's is served by its
 * one normal within ISM_SHEET_GROUP_MAX_ANGLE. Leaves those sets in s (parent, size, sum)
 * and every other member a set of its own. */
static void whole_half_sheets(fan_ws *s, const uint32_t *corner, uint32_t k, size_t np,
                              const float *cn)
{
    for (uint32_t i = 0; i < k; i++)
        singleton(s, i, corner, cn);
    for (size_t p = 0; p < np; p++) {
        uint32_t ra = ism_an_uf_find(s->parent, s->pair[p].a);
        uint32_t rb = ism_an_uf_find(s->parent, s->pair[p].b);
        if (ra != rb)
            join_sets(s, ra, rb);
    }
    const double cmin = cos(ISM_SHEET_GROUP_MAX_ANGLE);
    for (uint32_t i = 0; i < k; i++)
        s->whole[i] = 1;
    for (uint32_t i = 0; i < k; i++) {
        uint32_t r = ism_an_uf_find(s->parent, i);
        double len = ism_norm3(s->sum + 3 * r);
        const float *n = cn + 3 * (size_t)corner[i];
        double c = len > 0 && isfinite(len)
                       ? ((double)n[0] * s->sum[3 * r] + (double)n[1] * s->sum[3 * r + 1] +
                          (double)n[2] * s->sum[3 * r + 2]) / len
                       : -1;
        if (c < cmin)
            s->whole[r] = 0; /* at its root first: members read it below */
    }
    for (uint32_t i = 0; i < k; i++) {
        uint32_t r = ism_an_uf_find(s->parent, i);
        s->whole[i] = s->whole[r];
    }
    for (uint32_t i = 0; i < k; i++) /* the others start apart for the fans */
        if (!s->whole[i])
            singleton(s, i, corner, cn);
}

/* The k >= 2 marked corners corner[] at vertex v; start: per vertex w, its marked corners'
 * run start[w]..start[w + 1] (empty: w carries no mark).
 * A half-sheet whose triangles' normals one normal serves within ISM_SHEET_GROUP_MAX_ANGLE
 * (a sheet with a tangent plane at v) is joined whole; any other (a cone's nappe, a pinch
 * point's fan) is joined into fans, closest pairs first, while the fan's normal stays within
 * ISM_SHEET_FAN_MAX_ANGLE of each member's. */
static void join_vertex(const ism_mesh *m, uint32_t v, const uint32_t *corner, uint32_t k,
                        const size_t *start, float *cn, fan_ws *s)
{
    size_t np = fan_pairs(m, v, corner, k, start, cn, s);
    if (!np)
        return;
    whole_half_sheets(s, corner, k, np, cn);
    const double cmin = cos(ISM_SHEET_FAN_MAX_ANGLE);
    for (size_t p = 0; p < np; p++) {
        if (s->whole[s->pair[p].a])
            continue;
        uint32_t ra = ism_an_uf_find(s->parent, s->pair[p].a);
        uint32_t rb = ism_an_uf_find(s->parent, s->pair[p].b);
        if (ra == rb)
            continue;
        double sum[3], u[3];
        for (int d = 0; d < 3; d++)
            sum[d] = s->sum[3 * ra + d] + s->sum[3 * rb + d];
        double len = ism_norm3(sum);
        if (!(len > 0) || !isfinite(len))
            continue;
        for (int d = 0; d < 3; d++)
            u[d] = sum[d] / len;
        if (serves_all(s, corner, k, ra, rb, u, cn, cmin))
            join_sets(s, ra, rb);
    }
    /* every member read its own normal above; now the sets of two or more get theirs */
    for (uint32_t i = 0; i < k; i++) {
        uint32_t r = ism_an_uf_find(s->parent, i);
        if (s->size[r] < 2)
            continue;
        double len = ism_norm3(s->sum + 3 * r);
        for (int d = 0; d < 3; d++)
            cn[3 * (size_t)corner[i] + d] = (float)(s->sum[3 * r + d] / len);
    }
}

bool ism_sheet_groups_join(const ism_mesh *m, const uint8_t *mark, float *cn)
{
    size_t nc = 3 * m->ntris;
    size_t *start = calloc(m->nverts + 2, sizeof *start);
    if (!start)
        return false;
    for (size_t c = 0; c < nc; c++)
        if (mark[c])
            start[m->tri[c] + 2]++;
    size_t cap = 0;
    for (size_t v = 0; v < m->nverts; v++) {
        cap = start[v + 2] > cap ? start[v + 2] : cap;
        start[v + 2] += start[v + 1];
    }
    uint32_t *corner = malloc((start[m->nverts + 1] + 1) * sizeof *corner);
    fan_ws s = {0};
    bool ok = corner && fan_ws_alloc(&s, cap ? cap : 1);
    if (ok) {
        for (size_t c = 0; c < nc; c++) /* counting sort: start[v + 1] is v's next slot */
            if (mark[c])
                corner[start[m->tri[c] + 1]++] = (uint32_t)c;
        for (size_t v = 0; v < m->nverts; v++)
            if (start[v + 1] - start[v] >= 2)
                join_vertex(m, (uint32_t)v, corner + start[v],
                            (uint32_t)(start[v + 1] - start[v]), start, cn, &s);
    }
    fan_ws_free(&s);
    free(corner);
    free(start);
    return ok;
}
