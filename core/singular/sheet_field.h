/* sheet_field.h — the lattice vertices the double-sheet stage looks at, and what it knows at
 * each: f, ∇f, the Hessian's dominant eigenpair (n, λ), and, once n is oriented consistently
 * between neighbours (sheet_orient.h), ψ = ∇f·n — the field that changes sign across a
 * double sheet f = g² (there ∇f = 2g∇g and n = ±∇g/|∇g|, so ψ = ±2g|∇g|). Evaluations run
 * on several threads, each vertex at most once per quantity. */
#ifndef ISM_SHEET_FIELD_H
#define ISM_SHEET_FIELD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/eval/eval.h"
#include "core/octree/grid.h"
#include "core/singular/key_map.h"

/* What a vertex knows (bits of ism_sheet_vertex.have). */
enum ism_sf_have {
    ISM_SF_F = 1,        /* f */
    ISM_SF_GRAD = 2,     /* f and ∇f */
    ISM_SF_JET = 4,      /* f, ∇f, n, λ (n unoriented) */
    ISM_SF_NO_DIR = 8,   /* the Hessian has no dominant direction here (zero or not finite) */
    ISM_SF_ORIENTED = 16 /* n oriented against its neighbours, psi set */
};

typedef struct ism_sheet_vertex {
    double f, g[3];
    double n[3], lam;    /* unit eigenvector of the Hessian's eigenvalue of largest |λ| */
    double psi;          /* ∇f·n once oriented */
    uint8_t have;        /* enum ism_sf_have */
} ism_sheet_vertex;

typedef struct ism_sheet_field {
    const ism_tape *f;
    const ism_grid *grid;
    int threads;
    ism_eval_ws **ws;    /* one per thread */
    ism_key_map map;     /* lattice key -> vertex index */
    ism_sheet_vertex *v;
    size_t cap;
    uint64_t evals_point, evals_grad, evals_jet;
} ism_sheet_field;

/* False when out of memory (the field is then freed). */
bool ism_sheet_field_init(ism_sheet_field *sf, const ism_tape *f, const ism_grid *g,
                          int threads);
void ism_sheet_field_free(ism_sheet_field *sf);

/* The index of the lattice point with this key (lattice_key.h), added knowing nothing when
 * new; ISM_KEY_NONE when out of memory. */
uint32_t ism_sheet_field_vertex(ism_sheet_field *sf, uint64_t key);

/* World position of vertex i (bit-identical to the octree's lattice points). */
void ism_sheet_field_point(const ism_sheet_field *sf, uint32_t i, double p[3]);

/* Makes every listed vertex (duplicates allowed) know `what` (ISM_SF_F, ISM_SF_GRAD or
 * ISM_SF_JET). False when out of memory. */
bool ism_sheet_field_need(ism_sheet_field *sf, const uint32_t *idx, size_t n, int what);

/* The Hessian's eigenpair of largest |λ| at a point: false when it has none (H zero or not
 * finite). */
bool ism_sheet_dominant(const double h[6], double n[3], double *lam);

/* Bytes held (for budgets). */
size_t ism_sheet_field_bytes(const ism_sheet_field *sf);

#endif
