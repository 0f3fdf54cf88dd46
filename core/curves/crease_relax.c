/* crease_relax.c — the thin triangles beside a crease fattened by moving their corner off
 * the crease (crease_relax.h). The candidates' triangles are gathered once (a CSR of vertex
 * to triangles over the candidates only); each candidate moves to the mean of its star's
 * other corners on the surface, kept only where that helps: same branch, no triangle turned
 * over, the star's smallest angle larger. */
#include "core/curves/crease_relax.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/util/grow.h"
#include "core/util/vec3.h"

#define NONE CUT_NONE
/* A star triangle's new normal keeps this cosine with its old one (60°: not turned over). */
#define CREASE_RELAX_TURN_COS 0.5
/* Newton steps along the branch's gradient back onto its zero set (the mean of a star lies
 * within its sagitta of the surface: two or three suffice). */
#define CREASE_RELAX_NEWTON 4
/* The shortest move toward the mean tried, as a share of the whole way (1, 1/2, 1/4). */
#define CREASE_RELAX_LEAST_STEP 0.25
/* Triangles round a vertex handled (a mesh vertex has 3–12; more: left where it is). */
#define CREASE_RELAX_STAR_MAX 64

/* The largest cosine of triangle tv's corner angles with its corner `moved` at p (NONE:
 * none): the cosine of its smallest angle, compared as such (no acos per triangle). */
static double max_corner_cos(const ism_mesh *m, const uint32_t *tv, uint32_t moved,
                             const double *p)
{
    const double *q[3];
    for (int i = 0; i < 3; i++)
        q[i] = tv[i] == moved ? p : m->pos + 3 * (size_t)tv[i];
    double best = -1;
    for (int i = 0; i < 3; i++) {
        double u[3], v[3];
        for (int c = 0; c < 3; c++) {
            u[c] = q[(i + 1) % 3][c] - q[i][c];
            v[c] = q[(i + 2) % 3][c] - q[i][c];
        }
        double nn = ism_norm3(u) * ism_norm3(v);
        best = fmax(best, nn > 0 ? ism_dot3(u, v) / nn : 1);
    }
    return best;
}

/* Candidates: third corners (off the crease) of thin triangles on crease edges. */
static void mark_candidates(cut_state *s, size_t k, const uint8_t *on, uint8_t *cand)
{
    const ism_mesh *m = s->m;
    const double thin_cos = cos(CREASE_RELAX_THIN_DEG * (M_PI / 180));
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *tv = m->tri + 3 * t;
        for (int i = 0; i < 3; i++) {
            uint32_t a = tv[i], b = tv[(i + 1) % 3], c = tv[(i + 2) % 3];
            if (on[c] || !on[a] || !on[b])
                continue;
            uint32_t e = cut_find_cut_edge(s, a, b);
            if (e != NONE && s->c->edges[e].fn == k &&
                max_corner_cos(m, tv, NONE, NULL) > thin_cos)
                cand[c] = 1;
        }
    }
}

/* What a move of a star's centre is measured against, the same for every move tried: its
 * triangles' normals and the cosine of their smallest angle. */
typedef struct star_before {
    double normal[CREASE_RELAX_STAR_MAX][3];
    double worst;
} star_before;

static void measure_star(const ism_mesh *m, const uint32_t *star, size_t n, star_before *sb)
{
    sb->worst = -1;
    for (size_t i = 0; i < n; i++) {
        const uint32_t *tv = m->tri + 3 * (size_t)star[i];
        cut_tri_normal(m, tv, NONE, NULL, sb->normal[i]);
        sb->worst = fmax(sb->worst, max_corner_cos(m, tv, NONE, NULL));
    }
}

/* Whether v may go to p (on its branch A's zero set already): p on branch A, none of its
 * triangles star[0..n) turned over, their smallest angle larger (each of them: the star's
 * smallest angle after the move is larger than before). */
static bool helps(cut_state *s, uint32_t v, uint32_t A, const uint32_t *star, size_t n,
                  const star_before *sb, const double *p)
{
    const ism_mesh *m = s->m;
    for (size_t i = 0; i < n; i++) {
        const uint32_t *tv = m->tri + 3 * (size_t)star[i];
        const double *o = sb->normal[i];
        double q[3];
        cut_tri_normal(m, tv, v, p, q);
        if (!(ism_dot3(o, q) >= CREASE_RELAX_TURN_COS * ism_norm3(o) * ism_norm3(q)) ||
            !(max_corner_cos(m, tv, v, p) < sb->worst))
            return false;
    }
    uint32_t B; /* last: the branch costs a tape shortening */
    return ism_branches_at(s->branches, p, &B) && B == A;
}

/* Whether the star of v (its triangles star[0..n)) is a closed fan: each neighbour in
 * exactly two of them (not at the box, not on a non-manifold edge, where moving v would
 * tear the surface or leave the locus). */
static bool closed_fan(const ism_mesh *m, uint32_t v, const uint32_t *star, size_t n)
{
    for (size_t i = 0; i < n; i++)
        for (int j = 0; j < 3; j++) {
            uint32_t w = m->tri[3 * (size_t)star[i] + j], seen = 0;
            for (size_t k = 0; w != v && k < n; k++)
                for (int c = 0; c < 3; c++)
                    seen += m->tri[3 * (size_t)star[k] + c] == w;
            if (w != v && seen != 2)
                return false;
        }
    return true;
}

/* splitmix64's finaliser: every bit of x spread over the result. */
static uint64_t mix64(uint64_t x)
{
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
}

/* The signature of v's star as relax_vertex reads it: each triangle's corners in order, their
 * places (bit for bit) and whether they lie on the crease, summed over the triangles (their
 * order is not the star's). Never 0. */
static uint64_t star_signature(const ism_mesh *m, uint32_t v, const uint32_t *star, size_t n,
                               const uint8_t *on)
{
    uint64_t sum = mix64(v);
    for (size_t i = 0; i < n; i++) {
        uint64_t h = 0;
        for (int j = 0; j < 3; j++) {
            uint32_t w = m->tri[3 * (size_t)star[i] + j];
            h = mix64(h ^ ((uint64_t)w << 1 | on[w]));
            for (int c = 0; c < 3; c++) {
                uint64_t bits;
                memcpy(&bits, m->pos + 3 * (size_t)w + c, sizeof bits);
                h = mix64(h ^ bits);
            }
        }
        sum += h;
    }
    return sum ? sum : 1;
}

void cut_relax_memo_free(cut_relax_memo *memo)
{
    free(memo->failed);
    memset(memo, 0, sizeof *memo);
}

/* Moves candidate v (its triangles star[0..n)) toward the mean of its star's other corners
 * (all the way, else a half or a quarter of it: the whole way may cross the crease where it
 * bends round v), put back on its branch, when that helps; true when moved. */
static bool relax_vertex(cut_state *s, uint32_t v, const uint32_t *star, size_t n,
                         const uint8_t *on)
{
    ism_mesh *m = s->m;
    double *pv = m->pos + 3 * (size_t)v, mean[2][3] = {{0, 0, 0}, {0, 0, 0}};
    size_t count[2] = {0, 0};
    for (size_t i = 0; i < n; i++)
        for (int j = 0; j < 3; j++) {
            uint32_t w = m->tri[3 * (size_t)star[i] + j];
            count[0] += w != v;
            count[1] += w != v && !on[w];
            for (int c = 0; w != v && c < 3; c++) {
                mean[0][c] += m->pos[3 * (size_t)w + c];
                mean[1][c] += on[w] ? 0 : m->pos[3 * (size_t)w + c];
            }
        }
    for (int k = 0; k < 2; k++)
        for (int c = 0; c < 3 && count[k]; c++)
            mean[k][c] /= (double)count[k];
    uint32_t A;
    if (!closed_fan(m, v, star, n) || !ism_branches_at(s->branches, pv, &A) ||
        A == ISM_BRANCH_NONE)
        return false;
    star_before sb;
    measure_star(m, star, n, &sb);
    for (int k = 0; k < 2; k++) /* the whole star's mean, then its corners' off the crease */
    for (double lambda = 1; count[k] && lambda >= CREASE_RELAX_LEAST_STEP; lambda *= 0.5) {
        double p[3];
        for (int c = 0; c < 3; c++)
            p[c] = pv[c] + lambda * (mean[k][c] - pv[c]);
        ism_branches_project(s->branches, A, CREASE_RELAX_NEWTON, s->tol, p);
        if (!helps(s, v, A, star, n, &sb, p))
            continue;
        float nrm[3];
        cut_normal_at(s, p, m->normal + 3 * (size_t)v, nrm);
        memcpy(pv, p, sizeof p);
        memcpy(m->normal + 3 * (size_t)v, nrm, sizeof nrm);
        return true;
    }
    return false;
}

bool cut_crease_relax(cut_state *s, size_t k, cut_relax_memo *memo, size_t *moved)
{
    const ism_mesh *m = s->m;
    size_t nv = m->nverts, old = memo->cap;
    *moved = 0;
    uint8_t *on = calloc(nv + 1, 1), *cand = calloc(nv + 1, 1);
    uint32_t *first = calloc(nv + 2, sizeof *first), *tris = NULL;
    bool ok = on && cand && first &&
              ism_grow((void **)&memo->failed, &memo->cap, nv + 1, sizeof *memo->failed,
                       CUT_FIRST);
    if (ok)
        memset(memo->failed + old, 0, (memo->cap - old) * sizeof *memo->failed);
    for (size_t i = 0; ok && i < s->c->nedges; i++)
        if (s->c->edges[i].fn == k)
            on[s->c->edges[i].a] = on[s->c->edges[i].b] = 1;
    if (ok)
        mark_candidates(s, k, on, cand);
    for (size_t i = 0; ok && i < 3 * m->ntris; i++) /* the candidates' stars, as a CSR */
        first[m->tri[i] + 1] += cand[m->tri[i]];
    for (size_t v = 0; ok && v < nv; v++)
        first[v + 1] += first[v];
    if (ok && first[nv] && !(tris = malloc(first[nv] * sizeof *tris)))
        ok = false;
    for (size_t t = 0; ok && tris && t < m->ntris; t++)
        for (int j = 0; j < 3; j++) {
            uint32_t v = m->tri[3 * t + j];
            if (cand[v])
                tris[first[v]++] = (uint32_t)t;
        }
    for (size_t v = nv; ok && tris && v > 0; v--) /* first[v] ran to the next one's start */
        first[v] = first[v - 1];
    if (ok && tris)
        first[0] = 0;
    for (size_t v = 0; ok && tris && v < nv; v++) {
        size_t n = first[v + 1] - first[v];
        if (!cand[v] || n < 3 || n > CREASE_RELAX_STAR_MAX)
            continue;
        uint64_t sig = star_signature(m, (uint32_t)v, tris + first[v], n, on);
        if (memo->failed[v] == sig)
            continue; /* the same star failed before */
        bool went = relax_vertex(s, (uint32_t)v, tris + first[v], n, on);
        memo->failed[v] = went ? 0 : sig;
        *moved += went;
    }
    free(on);
    free(cand);
    free(first);
    free(tris);
    return ok;
}
