/**
 * @file TetGeometry.h
 * @brief Per-tet geometry kernel shared by the assembly loops of
 * DiscreteDivergence and FiniteElement, and its per-mesh cache.
 *
 * Private header of the Solvers library (not installed, not part of its API).
 */
#pragma once

#include "TetMesh.h"

#include <cstddef>
#include <cstdint>
#include <vector>

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

/// The geometry from V_t and the six off-diagonal g_ab: the diagonal is
/// g_aa = -sum_b g_ab (rows sum to 0; TransCut Sec. 3.3: w_iit = -(w_ijt +
/// w_ikt + w_ilt); for the FEM, sum_a grad(beta_a) = 0). Used by
/// ComputeTetGeometry and by the per-tet geometry cache, so both give the
/// same bits.
inline TetGeometry MakeTetGeometry(double volume, double g01, double g02, double g03, double g12,
  double g13, double g23)
{
  const double g00 = -(g01 + g02 + g03), g11 = -(g01 + g12 + g13), g22 = -(g02 + g12 + g23),
               g33 = -(g03 + g13 + g23);
  return TetGeometry{ volume,
    { { g00, g01, g02, g03 }, { g01, g11, g12, g13 }, { g02, g12, g22, g23 },
      { g03, g13, g23, g33 } } };
}

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
  return MakeTetGeometry(sixV * (1.0 / 6.0), g01, g02, g03, g12, g13, g23);
}

/**
 * V_t and the six off-diagonal g_ab of every tet (7 doubles per tet), kept
 * between assemblies of the same geometry (TetMesh::GetGeometryRevision()):
 * they do not depend on the coefficients, so a re-assembly after a material
 * or light change only multiplies them by the coefficients and scatters.
 * The values are those ComputeTetGeometry returns, so an assembly from the
 * cache has the same bits as one that computes the geometry.
 */
class TetGeometryCache
{
public:
  static constexpr int Stride = 7;

  /// True if the cache holds the geometry of this mesh's current points.
  bool IsValidFor(const TetMesh& mesh) const
  {
    return Revision_ != 0 && Revision_ == mesh.GetGeometryRevision() &&
      Values_.size() == Stride * static_cast<size_t>(mesh.GetNumberOfTets());
  }

  /// The geometry of tet t (the cache must be valid).
  TetGeometry Get(size_t t) const
  {
    const double* o = Values_.data() + Stride * t;
    return MakeTetGeometry(o[0], o[1], o[2], o[3], o[4], o[5], o[6]);
  }

  /// Computes the geometry of tet t of the mesh and stores it (during a fill).
  TetGeometry ComputeAndStore(const double* points, const int* tv, size_t t)
  {
    const TetGeometry g = ComputeTetGeometry(points + 3 * static_cast<size_t>(tv[0]),
      points + 3 * static_cast<size_t>(tv[1]), points + 3 * static_cast<size_t>(tv[2]),
      points + 3 * static_cast<size_t>(tv[3]));
    double* o = Values_.data() + Stride * t;
    o[0] = g.Volume;
    o[1] = g.Stiffness[0][1];
    o[2] = g.Stiffness[0][2];
    o[3] = g.Stiffness[0][3];
    o[4] = g.Stiffness[1][2];
    o[5] = g.Stiffness[1][3];
    o[6] = g.Stiffness[2][3];
    return g;
  }

  /// Start a fill for this mesh (invalid until EndFill).
  void BeginFill(const TetMesh& mesh)
  {
    Revision_ = 0;
    Values_.resize(Stride * static_cast<size_t>(mesh.GetNumberOfTets()));
  }
  void EndFill(const TetMesh& mesh) { Revision_ = mesh.GetGeometryRevision(); }

  /// Bytes held.
  size_t GetMemoryBytes() const { return Values_.capacity() * sizeof(double); }

private:
  std::uint64_t Revision_ = 0;
  std::vector<double> Values_;
};

} // namespace translucency
