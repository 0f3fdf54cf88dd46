/* miranda.h — a proof that ∇f has a zero near a point no certificate can pin down (a contact
 * of two sheets, point_cert.h): the Poincaré–Miranda theorem on a cube in the Hessian's
 * eigenframe. With F̃_i(s) = R_i · ∇f(p + Rᵀs) on the cube |s_j| ≤ ρ, if each F̃_i has one
 * strict sign on the face s_i = ρ and the opposite one on s_i = −ρ, then F̃ — so ∇f — has
 * a zero in the cube (a continuous-map fact: no uniqueness, no certificate of f = 0 there).
 *
 *           s_N = +ρ: F̃_N > 0                touching spheres, (x²+y²+z²)² − 4x²:
 *          ┌───────────┐                     F̃_e = −8x + …   (strict on the e faces),
 *   F̃_e>0  │     •p    │ F̃_e<0               F̃_N = 4|w|²w_N (strict on the N faces,
 *          └───────────┘                     ≥ 4ρ³ there; rounding of ∇f ~1e-16 f's terms)
 *           s_N = −ρ: F̃_N < 0
 *
 * Each face is cut into MIRANDA_PIECES² pieces, F̃_i over a piece enclosed by the Taylor
 * form F̃_i(c) + Σ_d t_d R_i H(c) R_dᵀ + ½ Σ_de t_d t_e D³f(hull)[R_i, R_d, R_e] (|t| ≤ h;
 * D³f over the piece's axis-aligned hull): the mean-value form with H over the hull loses
 * a product's cancellation, s₁s₂'s ∇s₁∇s₂ᵀ + ∇s₂∇s₁ᵀ, to an O(h) width. */
#ifndef ISM_SING_MIRANDA_H
#define ISM_SING_MIRANDA_H

#include <stdbool.h>
#include <stdint.h>
#include "core/singular/jet4.h"

/* Tries cubes of half-width ρ = rmin, rmin × 10, ... up to rmax around p in the
 * eigenframe of the Hessian at p. True with *radius = √3 ρ (a ball about p holding the
 * cube, hence the zero) for the first that passes. *evals counts jet evaluations. */
bool ism_miranda_zero(ism_jet4_ws *w, const double p[3], double rmin, double rmax,
                      double *radius, uint64_t *evals);

#endif
