/**
 * @file TetContributions.h
 * @brief The element matrices of one tet for the two vertex discretisations
 * (TransCut's discrete divergence, eq. 13-14, and the consistent P1 FEM),
 * shared by their serial assemblies (DiscreteDivergence, FiniteElement) and
 * the distributed one (Solvers/Parallel/DistributedVertexSolver), so the
 * three use the same expressions and bits.
 *
 * Private header of the Solvers library (not installed, not part of its API).
 */
#pragma once

#include "TetGeometry.h"

namespace translucency
{

/**
 * Divergence: diag[a] = 4 kappa_t g_aa + V_t mu_a (eq. 13, the tet's share
 * of -4 sum_j w_ij + V_i mu(x_i)), off = 4 kappa_t g_ab for the pairs 01,
 * 02, 03, 12, 13, 23 (eq. 14: M_ij = 4 w_ij). mu: mu_a, sigma: sigma_s'
 * (1/mm) of the tet in this channel.
 */
inline void DivergenceTetMatrix(
  const TetGeometry& geometry, double mu, double sigma, double diag[4], double off[6])
{
  const double(&g)[4][4] = geometry.Stiffness; // g_ab = N_a.N_b / (36 V_t)
  const double four = 4.0 / (3.0 * (mu + sigma)); // 4 kappa_t
  const double mass = geometry.Volume * mu;        // V_t mu_t: the tet's share of V_i mu(x_i)
  diag[0] = four * g[0][0] + mass;
  diag[1] = four * g[1][1] + mass;
  diag[2] = four * g[2][2] + mass;
  diag[3] = four * g[3][3] + mass;
  off[0] = four * g[0][1];
  off[1] = four * g[0][2];
  off[2] = four * g[0][3];
  off[3] = four * g[1][2];
  off[4] = four * g[1][3];
  off[5] = four * g[2][3];
}

/**
 * FEM: 4 x (stiffness kappa_t V_t grad(beta_a).grad(beta_b) + consistent
 * mass (V_t / 20)(1 + delta_ab) mu_t), same layout as DivergenceTetMatrix.
 */
inline void FiniteElementTetMatrix(
  const TetGeometry& geometry, double mu, double sigma, double diag[4], double off[6])
{
  const double(&g)[4][4] = geometry.Stiffness;
  const double four = 4.0 / (3.0 * (mu + sigma)); // 4 kappa_t
  // 4 x consistent mass (V_t / 20)(1 + delta_ab) mu_t: V_t mu_t / 5 off the
  // diagonal, twice that on it.
  const double mass = geometry.Volume * mu * 0.2;
  const double mass2 = mass + mass;
  diag[0] = four * g[0][0] + mass2;
  diag[1] = four * g[1][1] + mass2;
  diag[2] = four * g[2][2] + mass2;
  diag[3] = four * g[3][3] + mass2;
  off[0] = four * g[0][1] + mass;
  off[1] = four * g[0][2] + mass;
  off[2] = four * g[0][3] + mass;
  off[3] = four * g[1][2] + mass;
  off[4] = four * g[1][3] + mass;
  off[5] = four * g[2][3] + mass;
}

/// FEM boundary triangle of area S_f with the mismatch factor A of its
/// tet's eta: 4 x the consistent Robin mass (S_f / 12)(1 + delta_ab) / (2 A)
/// is `robin` off the diagonal and 2 `robin` on it; 4 x the consistent load
/// at vertex a is `load` (q_a + q_a + q_b + q_c) (TransCut eq. 2).
inline void FiniteElementRobin(double area, double a, double fdr, double& robin, double& load)
{
  robin = area / (6.0 * a);
  load = 2.0 * area / (3.0 * a * (1.0 - fdr));
}

/// Divergence boundary vertex with boundary area S_i and mismatch A of its
/// area-weighted eta: the diagonal term 2 S_i / (3 A) (eq. 13) and the
/// right-hand side 8 S_i q_i / (3 A (1 - Fdr)) (eq. 12).
inline double DivergenceRobinDiagonal(double s, double a)
{
  return 2.0 * s / (3.0 * a);
}
inline double DivergenceRobinLoad(double s, double q, double a, double fdr)
{
  return 8.0 * s * q / (3.0 * a * (1.0 - fdr));
}

} // namespace translucency
