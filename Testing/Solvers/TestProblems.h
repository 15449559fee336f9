/**
 * @file TestProblems.h
 * @brief Manufactured-solution machinery shared by the solver tests (no VTK).
 *
 * The convergence tests of TestDiscreteDivergence, TestFiniteElement,
 * TestGridSolver and TestQuadGraph solve for phi = exp(a.x) with
 * |a|^2 = mu_a / kappa (so div(kappa grad phi) - mu_a phi = 0) on a box, with
 * Robin data q = (1 - Fdr)/4 (phi + 2 A kappa dphi/dn), in three channels
 * (ConvergenceChannels), and report relative vertex errors and convergence
 * orders over a refinement study. Each test keeps its own mesh, boundary data
 * placement, assertions and tolerances; this header holds only the pieces they
 * share. It also holds the ErrorMessage / Contains helpers of the input-check
 * tests, and MakeProblem, the one builder of the DiffusionProblem the solver
 * tests fill in by hand.
 */
#pragma once

#include "DiffusionSolver.h"
#include "Error.h"
#include "OpticalProperties.h"
#include "TetMesh.h"

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <ostream>
#include <string>
#include <vector>

namespace translucency
{
namespace testing
{

/// The DiffusionProblem of a solver test: borrows `mesh` and `material`, and
/// `irradiance` (q, 3 values per point, W/mm^2) and the interior `sources`
/// when given; every other member keeps its default (no lights, no uniform
/// irradiance, shadows on, the surface collimated model), for the test to set.
/// The borrowed objects must outlive the problem (temporaries are refused).
inline DiffusionProblem MakeProblem(const TetMesh& mesh, const OpticalProperties& material)
{
  DiffusionProblem problem;
  problem.Mesh = &mesh;
  problem.Material = &material;
  return problem;
}

inline DiffusionProblem MakeProblem(
  const TetMesh& mesh, const OpticalProperties& material, const std::vector<double>& irradiance)
{
  DiffusionProblem problem = MakeProblem(mesh, material);
  problem.Irradiance = &irradiance;
  return problem;
}

inline DiffusionProblem MakeProblem(const TetMesh& mesh, const OpticalProperties& material,
  const std::vector<double>& irradiance, const Sources& sources)
{
  DiffusionProblem problem = MakeProblem(mesh, material, irradiance);
  problem.InteriorSources = &sources;
  return problem;
}

DiffusionProblem MakeProblem(
  const TetMesh&, const OpticalProperties&, std::vector<double>&&) = delete;
DiffusionProblem MakeProblem(
  const TetMesh&, const OpticalProperties&, std::vector<double>&&, const Sources&) = delete;

/// Absorption mu_a and reduced scattering sigma_s' (1/mm) of the three
/// channels of the convergence tests: skin1 red, marble red and apple blue
/// (absorption lengths 1/|a| of 3.7, 8.5 and 1.9 mm).
struct ChannelMaterials
{
  double MuA[3];
  double Sigma[3];
};

inline ChannelMaterials ConvergenceChannels()
{
  const MaterialPreset& skin = FindMaterialPreset("skin1");
  const MaterialPreset& marble = FindMaterialPreset("marble");
  const MaterialPreset& apple = FindMaterialPreset("apple");
  return ChannelMaterials{ { skin.Absorption[0], marble.Absorption[0], apple.Absorption[2] },
    { skin.ReducedScattering[0], marble.ReducedScattering[0], apple.ReducedScattering[2] } };
}

/// phi_c = exp(a_c.x) per channel c, with a_c along direction and
/// |a_c|^2 = mu_a / kappa, kappa = 1 / (3 (mu_a + sigma_s')) (mm): a solution
/// of div(kappa grad phi) - mu_a phi = 0 in a homogeneous medium.
struct ExponentialSolution
{
  std::array<Eigen::Vector3d, 3> A; ///< a_c (1/mm)
  std::array<double, 3> Kappa;      ///< kappa_c (mm)

  ExponentialSolution(const double muA[3], const double sigma[3], const Eigen::Vector3d& direction)
  {
    for (int c = 0; c < 3; ++c)
    {
      Kappa[c] = 1.0 / (3.0 * (muA[c] + sigma[c]));
      A[c] = std::sqrt(muA[c] / Kappa[c]) * direction.normalized();
    }
  }

  /// phi_c(x).
  double operator()(int c, const Eigen::Vector3d& x) const { return std::exp(A[c].dot(x)); }

  /// Robin data q = (1 - Fdr)/4 (phi + 2 A kappa dphi/dn) of channel c at x
  /// on a face with outward unit normal n (fdr = Fdr, bigA = A of the
  /// boundary's refractive index).
  double RobinData(
    int c, const Eigen::Vector3d& x, const Eigen::Vector3d& normal, double fdr, double bigA) const
  {
    const double phi = (*this)(c, x);
    return (1.0 - fdr) / 4.0 * (phi + 2.0 * bigA * Kappa[c] * A[c].dot(normal) * phi);
  }
};

/// Max and RMS over i in [0, n) of |value(i) - exact(i)| / exact(i).
template <typename Value, typename Exact>
void RelativeErrors(int n, Value value, Exact exact, double& max, double& rms)
{
  max = 0.0;
  double sum2 = 0.0;
  for (int i = 0; i < n; ++i)
  {
    const double e = exact(i);
    const double rel = std::abs(value(i) - e) / e;
    max = std::max(max, rel);
    sum2 += rel * rel;
  }
  rms = std::sqrt(sum2 / n);
}

/// Max and RMS relative errors per channel at one refinement level.
struct ConvergenceErrors
{
  std::array<double, 3> Max{}, Rms{};
};

/// Observed order of convergence between two levels halving the mesh size.
inline double ConvergenceOrder(double coarse, double fine)
{
  return std::log2(coarse / fine);
}

/// Writes "  n=<level> max <e> rms <e> (orders <max>, <rms>)" for each level
/// of channel c (no orders at the first level); levels[l] is the cells per
/// side of errors[l].
inline void WriteRefinementRow(
  std::ostream& out, const int* levels, const std::vector<ConvergenceErrors>& errors, int c)
{
  for (size_t l = 0; l < errors.size(); ++l)
  {
    out << "  n=" << levels[l] << " max " << errors[l].Max[c] << " rms " << errors[l].Rms[c];
    if (l > 0)
    {
      out << " (orders " << ConvergenceOrder(errors[l - 1].Max[c], errors[l].Max[c]) << ", "
          << ConvergenceOrder(errors[l - 1].Rms[c], errors[l].Rms[c]) << ")";
    }
  }
}

/// The message of the translucency::Error f() throws, or "" if none.
template <typename F>
std::string ErrorMessage(F f)
{
  try
  {
    f();
  }
  catch (const Error& e)
  {
    return e.what();
  }
  return "";
}

inline bool Contains(const std::string& text, const std::string& part)
{
  return text.find(part) != std::string::npos;
}

/// The tets with a vertex within `radius` of `centre` (a paint stroke's
/// footprint in the cache tests), in tet order.
inline std::vector<int> TetsNear(
  const TetMesh& mesh, const std::array<double, 3>& centre, double radius)
{
  std::vector<int> tets;
  for (int t = 0; t < mesh.GetNumberOfTets(); ++t)
  {
    const int* v = mesh.GetTet(t);
    for (int k = 0; k < 4; ++k)
    {
      const double* x = mesh.GetPoint(v[k]);
      const double d2 = (x[0] - centre[0]) * (x[0] - centre[0]) +
        (x[1] - centre[1]) * (x[1] - centre[1]) + (x[2] - centre[2]) * (x[2] - centre[2]);
      if (d2 < radius * radius)
      {
        tets.push_back(t);
        break;
      }
    }
  }
  return tets;
}

/// max |a - b| / max |b| (the difference itself when b is 0; 0 for equal
/// vectors); infinite when the sizes differ, so that every bound fails.
inline double RelativeDifference(const std::vector<double>& a, const std::vector<double>& b)
{
  if (a.size() != b.size())
  {
    return std::numeric_limits<double>::infinity();
  }
  double diff = 0.0, scale = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k)
  {
    diff = std::max(diff, std::abs(a[k] - b[k]));
    scale = std::max(scale, std::abs(b[k]));
  }
  return scale > 0.0 ? diff / scale : diff;
}

} // namespace testing
} // namespace translucency
