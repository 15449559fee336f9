/**
 * @file TetGeometry.h
 * @brief Per-tet geometry kernel shared by the assembly loops of
 * DiscreteDivergence and FiniteElement.
 *
 * Private header of the Solvers library (not installed, not part of its API).
 */
#pragma once

namespace translucency
{

/// Volume and geometric stiffness of one positively oriented tetrahedron.
struct TetGeometry
{
  /// V_t (mm^3), > 0 for a positively oriented tet.
  double Volume;
  /// g_ab = N_a.N_b / (36 V_t) (mm), symmetric, rows summing to 0.
  double Stiffness[4][4];
};

/// Computes the volume and the geometric stiffness g_ab of the tet (p0, p1,
/// p2, p3), each a pointer to 3 coordinates (mm). Inline: it is the inner
/// kernel of the assembly loops, and its expressions fix their bit patterns.
inline TetGeometry ComputeTetGeometry(
  const double* p0, const double* p1, const double* p2, const double* p3)
{
  const double e1x = p1[0] - p0[0], e1y = p1[1] - p0[1], e1z = p1[2] - p0[2];
  const double e2x = p2[0] - p0[0], e2y = p2[1] - p0[1], e2z = p2[2] - p0[2];
  const double e3x = p3[0] - p0[0], e3y = p3[1] - p0[1], e3z = p3[2] - p0[2];
  // N_a = 2 S_a n_a: twice the area times the unit normal of the face opposite
  // vertex a, pointing towards a, and grad(beta_a) = N_a / (6 V_t) (TransCut
  // eq. 4 notation).
  const double n1x = e2y * e3z - e2z * e3y, n1y = e2z * e3x - e2x * e3z,
               n1z = e2x * e3y - e2y * e3x;
  const double n2x = e3y * e1z - e3z * e1y, n2y = e3z * e1x - e3x * e1z,
               n2z = e3x * e1y - e3y * e1x;
  const double n3x = e1y * e2z - e1z * e2y, n3y = e1z * e2x - e1x * e2z,
               n3z = e1x * e2y - e1y * e2x;
  // Closed surface: the face area vectors sum to zero.
  const double n0x = -(n1x + n2x + n3x), n0y = -(n1y + n2y + n3y), n0z = -(n1z + n2z + n3z);
  const double sixV = e1x * n1x + e1y * n1y + e1z * n1z; // 6 V_t > 0
  // Geometric edge weights g_ab = w_abt / kappa_t. The faces opposite a and b
  // meet at the opposite edge kl with interior dihedral angle theta_kl:
  // n_a.n_b = -cos(theta_kl) and sin(theta_kl) = 3 V_t |kl| / (2 S_a S_b), so
  //   -(1/6) |kl| cot(theta_kl) = S_a S_b (n_a.n_b) / (9 V_t)
  //                             = N_a.N_b / (36 V_t)   (TransCut eq. 10, Sec. 3.3)
  // which is also the P1 element stiffness / kappa_t,
  // V_t grad(beta_a).grad(beta_b).
  const double scale = 1.0 / (6.0 * sixV);
  const double g01 = (n0x * n1x + n0y * n1y + n0z * n1z) * scale;
  const double g02 = (n0x * n2x + n0y * n2y + n0z * n2z) * scale;
  const double g03 = (n0x * n3x + n0y * n3y + n0z * n3z) * scale;
  const double g12 = (n1x * n2x + n1y * n2y + n1z * n2z) * scale;
  const double g13 = (n1x * n3x + n1y * n3y + n1z * n3z) * scale;
  const double g23 = (n2x * n3x + n2y * n3y + n2z * n3z) * scale;
  // Rows sum to 0: g_aa = -sum_b g_ab (TransCut Sec. 3.3: w_iit = -(w_ijt +
  // w_ikt + w_ilt); for the FEM, sum_a grad(beta_a) = 0).
  const double g00 = -(g01 + g02 + g03), g11 = -(g01 + g12 + g13), g22 = -(g02 + g12 + g23),
               g33 = -(g03 + g13 + g23);
  return TetGeometry{ sixV * (1.0 / 6.0),
    { { g00, g01, g02, g03 }, { g01, g11, g12, g13 }, { g02, g12, g22, g23 },
      { g03, g13, g23, g33 } } };
}

} // namespace translucency
