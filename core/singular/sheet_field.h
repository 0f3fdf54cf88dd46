/* sheet_field.h — the lattice vertices the double-sheet stage looks at, and what it knows at
 * each: f, ∇f, the Hessian's dominant eigenpair (n, λ), and, once n is oriented consistently
 * between neighbours (sheet_orient.h), ψ = (∇f·n)/λ — minus the Newton step to the stationary
 * point of f along n, the field that changes sign across a double sheet. Near f = g²·k
 * (k ≠ 0, either sign), ∇f ≈ 2gk∇g and H ≈ 2k∇g∇gᵀ, so n = ±∇g/|∇g| and ψ = ±g/|∇g|: the
 * signed distance to the sheet, whatever the sign of k (∇f·n alone would flip where k does).
 * Evaluations run on several threads, each vertex once. */
#ifndef ISM_SHEET_FIELD_H
#define ISM_SHEET_FIELD_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/eval/eval.h"
#include "core/octree/grid.h"
#include "core/singular/key_map.h"

/* What a vertex knows (bits of ism_sheet_vertex.have). */
enum ism_sf_have {
    ISM_SF_JET = 1,      /* f, ∇f, n, λ (n unoriented) */
    ISM_SF_NO_DIR = 2,   /* the Hessian has no dominant direction here (zero or not finite) */
    ISM_SF_ORIENTED = 4  /* n oriented against its neighbours, psi set */
};

typedef struct ism_sheet_vertex {
    double p[3];         /* world position (ism_grid_coord of its lattice point) */
    double f, g[3];
    double n[3], lam;    /* unit eigenvector of the Hessian's eigenvalue of largest |λ| */
    double psi;          /* (∇f·n)/λ once oriented */
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
    uint64_t evals_jet;
    const volatile int *cancel; /* polled by each parallel task (may be NULL) */
    double deadline_ms;         /* ism_now_ms() past which tasks stop (0 = none) */
    atomic_int stopped;         /* set once a task saw cancel or the deadline */
} ism_sheet_field;

/* False when out of memory (the field is then freed). */
bool ism_sheet_field_init(ism_sheet_field *sf, const ism_tape *f, const ism_grid *g,
                          int threads);

/* True (and sf->stopped set) when cancel is set or the deadline has passed: parallel tasks
 * then skip their work, leaving it undone (jets unknown, crossings not landed). */
bool ism_sheet_field_should_stop(ism_sheet_field *sf);
void ism_sheet_field_free(ism_sheet_field *sf);

/* The index of the lattice point with this key (lattice_key.h), added knowing nothing when
 * new; ISM_KEY_NONE when out of memory. */
uint32_t ism_sheet_field_vertex(ism_sheet_field *sf, uint64_t key);

/* World position of vertex i (bit-identical to the octree's lattice points). */
static inline const double *ism_sheet_field_point(const ism_sheet_field *sf, uint32_t i)
{
    return sf->v[i].p;
}

/* Makes every listed vertex (duplicates allowed) know its jet (ISM_SF_JET), each evaluated
 * once. False when out of memory. */
bool ism_sheet_field_jets(ism_sheet_field *sf, const uint32_t *idx, size_t n);

/* The Hessian's eigenpair of largest |λ| at a point: false when it has none (H zero or not
 * finite). */
bool ism_sheet_dominant(const double h[6], double n[3], double *lam);

#endif
