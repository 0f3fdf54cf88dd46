/* leaf_memo.c — the leaves of the last max_error round whose output the next round copies:
 * the two trees walked side by side, then every leaf sharing an edge segment or a face with a
 * split one struck out. */
#include "core/octree/leaf_memo.h"
#include "core/octree/node_lbox.h"
#include "core/util/grow.h"

#include <stdlib.h>
#include <string.h>

typedef struct walk {
    const ism_octree *before, *now;
    const int32_t *before_leaf; /* node of before -> its leaf index, or -1 */
    int32_t *match;             /* node of now -> leaf of before, or -1 */
    ism_node_lbox *split;       /* boxes of before's leaves that now splits */
    size_t nsplit, cap_split;
    bool ok;
} walk;

/* Nodes a (of before) and b (of now) are the same node. */
static void pair(walk *w, int32_t a, int32_t b)
{
    const ism_node *x = &w->before->nodes[a], *y = &w->now->nodes[b];
    if (y->state == ISM_NODE_SPLIT && x->state == ISM_NODE_SPLIT) {
        for (int k = 0; k < 8 && w->ok; k++)
            pair(w, x->child + k, y->child + k);
        return;
    }
    /* (the tape numbers may differ: either tape gives the same values in the leaf) */
    if (y->state == ISM_NODE_LEAF && x->state == ISM_NODE_LEAF &&
        ((y->flags ^ x->flags) & ISM_NODE_FLAG_BITS) == 0) {
        w->match[b] = w->before_leaf[a];
        return;
    }
    if (x->state == y->state)
        return; /* both empty */
    /* a leaf split now (or any other change): whatever shares a segment with it may emit
       otherwise */
    if (!ism_grow((void **)&w->split, &w->cap_split, w->nsplit + 1, sizeof *w->split, 64)) {
        w->ok = false;
        return;
    }
    w->split[w->nsplit++] = ism_node_lbox_of(w->before, x);
}

/* Strikes out the leaves of now under node i that share a segment or a face with box c. One
 * touching c at a corner alone keeps its output: what a leaf emits depends on its face
 * tiles (the leaves across its faces) and on the break points registered on its closed box
 * (breaks_near.h: corners of the leaves touching it), and the only point of c's closed box
 * on a corner-only neighbour's is that corner, a lattice point whatever c became. */
static void strike(walk *w, int32_t i, const ism_node_lbox *c)
{
    const ism_node *nd = &w->now->nodes[i];
    ism_node_lbox b = ism_node_lbox_of(w->now, nd);
    if (!ism_node_lboxes_touch(&b, c))
        return;
    if (nd->state == ISM_NODE_SPLIT)
        for (int k = 0; k < 8; k++)
            strike(w, nd->child + k, c);
    else if (ism_node_lboxes_share_segment(&b, c))
        w->match[i] = -1;
}

bool ism_leaf_memo_match(const ism_octree *before, const ism_octree *now, int32_t *reuse)
{
    walk w = {before, now, NULL, NULL, NULL, 0, 0, true};
    int32_t *before_leaf = malloc((before->n ? before->n : 1) * sizeof *before_leaf);
    w.match = malloc((now->n ? now->n : 1) * sizeof *w.match);
    if (!before_leaf || !w.match) {
        free(before_leaf);
        free(w.match);
        return false;
    }
    int32_t nleaves = 0;
    for (size_t i = 0; i < before->n; i++)
        before_leaf[i] = before->nodes[i].state == ISM_NODE_LEAF ? nleaves++ : -1;
    for (size_t i = 0; i < now->n; i++)
        w.match[i] = -1;
    w.before_leaf = before_leaf;
    if (before->n && now->n)
        pair(&w, 0, 0);
    for (size_t k = 0; k < w.nsplit && w.ok; k++)
        strike(&w, 0, &w.split[k]);
    size_t leaf = 0;
    for (size_t i = 0; i < now->n; i++)
        if (now->nodes[i].state == ISM_NODE_LEAF)
            reuse[leaf++] = w.match[i];
    free(before_leaf);
    free(w.match);
    free(w.split);
    return w.ok;
}

/* Room in out for nv more vertices, nt triangles and ns segments. */
static bool room(ism_cell_out *out, size_t nv, size_t nt, size_t ns)
{
    return ism_grow((void **)&out->verts, &out->cap_verts, out->nverts + nv, sizeof *out->verts,
                    256) &&
           ism_grow((void **)&out->tris, &out->cap_tris, out->ntris + nt, 3 * sizeof *out->tris,
                    256) &&
           ism_grow((void **)&out->segs, &out->cap_segs, out->nsegs + ns, 2 * sizeof *out->segs,
                    16);
}

bool ism_leaf_memo_reserve(const ism_leaf_memo *m, const int32_t *reuse, size_t n,
                           ism_cell_out *out)
{
    size_t nv = 0, nt = 0, ns = 0, most_v = 0, most_t = 0, fresh = 0;
    for (size_t i = 0; i < n; i++)
        if (reuse[i] >= 0) {
            const ism_leaf_rec *r = &m->rec[reuse[i]];
            nv += r->nv, nt += r->nt, ns += r->ns;
            most_v = r->nv > most_v ? r->nv : most_v;
            most_t = r->nt > most_t ? r->nt : most_t;
        } else {
            fresh++;
        }
    return room(out, nv + fresh * most_v, nt + fresh * most_t, ns);
}

bool ism_leaf_memo_copy(const ism_leaf_memo *m, size_t leaf, ism_cell_out *out,
                        ism_cell_stats *st, ism_cell_stats *added, float *error)
{
    const ism_leaf_rec *r = &m->rec[leaf];
    const ism_cell_out *src = &m->out[r->chunk];
    if (!room(out, r->nv, r->nt, r->ns))
        return false;
    /* indices were local to src (from r->v0 on); they become local to out */
    uint32_t shift = (uint32_t)out->nverts - (uint32_t)r->v0;
    if (r->nv) /* a leaf that emitted nothing may meet arrays never allocated */
        memcpy(out->verts + out->nverts, src->verts + r->v0, r->nv * sizeof *out->verts);
    out->nverts += r->nv;
    for (size_t i = 0; i < 3 * r->nt; i++)
        out->tris[3 * out->ntris + i] = src->tris[3 * r->t0 + i] + shift;
    out->ntris += r->nt;
    for (size_t i = 0; i < 2 * r->ns; i++)
        out->segs[2 * out->nsegs + i] = src->segs[2 * r->s0 + i] + shift;
    out->nsegs += r->ns;
    ism_cell_stats_add(st, &r->stats);
    *added = r->stats;
    *error = r->error;
    return true;
}

void ism_leaf_memo_free(ism_leaf_memo *m)
{
    for (size_t c = 0; m->out && c < m->nchunks; c++) {
        free(m->out[c].verts);
        free(m->out[c].tris);
        free(m->out[c].segs);
    }
    free(m->out);
    free(m->rec);
    memset(m, 0, sizeof *m);
}
