#include "DiffusionFrontEnd.h"
#include "ResourceLimits.h"

#include "DiffusionSolverFactory.h"
#include "Strings.h"
#include "VertexDiffusionSolver.h"

#include <cstring>

namespace translucency
{

DiffusionFrontEnd::DiffusionFrontEnd()
{
  SetSolver(GetDiffusionSolverNames().front());
}

DiffusionFrontEnd::~DiffusionFrontEnd() = default;

void DiffusionFrontEnd::SetSolver(const std::string& name)
{
  const DiffusionSolverRegistry::Entry& entry = GetDiffusionSolverRegistry().Get(name);
  if (Solver_ && entry.Name == SolverName_)
  {
    return;
  }
  Solver_ = entry.Create();
  SolverName_ = entry.Name;
  ForgetLast();
}

void DiffusionFrontEnd::SetIncrementalAssembly(bool on)
{
  IncrementalAssembly_ = on;
  if (!on)
  {
    ForgetLast();
  }
}

void DiffusionFrontEnd::ForgetLast()
{
  HaveLast_ = false;
  LastMaterial_ = OpticalProperties();
  LastIrradiance_.clear();
}

void DiffusionFrontEnd::Reset()
{
  ForgetLast();
  Mesh_.reset();
  ChangedTets_ = -1;
  Solver_->Reset();
}

std::vector<int> DiffusionFrontEnd::FindChangedTets(
  const OpticalProperties& a, const OpticalProperties& b, std::size_t limit)
{
  std::vector<int> changed;
  const std::size_t n = a.RefractiveIndex.size();
  const double* a0 = a.AbsorptionCoefficient.data();
  const double* a1 = b.AbsorptionCoefficient.data();
  const double* s0 = a.ReducedScatteringCoefficient.data();
  const double* s1 = b.ReducedScatteringCoefficient.data();
  for (std::size_t t = 0; t < n && changed.size() <= limit; ++t)
  {
    // Compared as bits (memcmp): a NaN that stays a NaN is no change, and a
    // value that changes in any way is one.
    if (std::memcmp(a0 + 3 * t, a1 + 3 * t, 3 * sizeof(double)) != 0 ||
      std::memcmp(s0 + 3 * t, s1 + 3 * t, 3 * sizeof(double)) != 0 ||
      std::memcmp(&a.RefractiveIndex[t], &b.RefractiveIndex[t], sizeof(double)) != 0)
    {
      changed.push_back(static_cast<int>(t));
    }
  }
  return changed;
}

bool DiffusionFrontEnd::Solve(std::shared_ptr<const TetMesh> mesh, OpticalProperties material,
  std::vector<double> irradiance, const DiffusionProblem& light, std::vector<double>& fluence,
  SolverReport& report)
{
  if (mesh != Mesh_)
  {
    Solver_->Reset(); // a new geometry: the previous solution is no start point
    Mesh_ = mesh;
    ForgetLast();
  }
  auto* vertex = dynamic_cast<VertexDiffusionSolver*>(Solver_.get());
  ChangedTets_ = -1;
  if (vertex)
  {
    // Same mesh (topology and points), only some tets' coefficients
    // changed since the last successful solve: found by comparing with the
    // coefficients cached from that solve. Another irradiance (a relight)
    // rebuilds the right-hand side too.
    const std::size_t numTets = material.RefractiveIndex.size();
    const auto limit = static_cast<std::size_t>(MaximumChangedFraction_ * numTets);
    if (IncrementalAssembly_ && HaveLast_ && LastMaterial_.RefractiveIndex.size() == numTets &&
      LastMaterial_.AbsorptionCoefficient.size() == material.AbsorptionCoefficient.size() &&
      LastMaterial_.ReducedScatteringCoefficient.size() ==
        material.ReducedScatteringCoefficient.size() &&
      LastIrradiance_.size() == irradiance.size())
    {
      const bool relit = std::memcmp(LastIrradiance_.data(), irradiance.data(),
                           irradiance.size() * sizeof(double)) != 0;
      std::vector<int> changed = FindChangedTets(LastMaterial_, material, limit);
      if (changed.size() <= limit)
      {
        ChangedTets_ = static_cast<long long>(changed.size());
        vertex->SetChangedTets(std::move(changed), relit);
      }
    }
  }
  ForgetLast(); // until this solve succeeds

  DiffusionProblem problem = light;
  problem.Mesh = mesh.get();
  problem.Material = &material;
  problem.Irradiance = &irradiance;
  bool solved = false;
  try
  {
    solved = Solver_->Solve(problem, fluence, report);
    if (solved)
    {
      // Never hand on a NaN/inf fluence as a result (e.g. a light power of
      // 1e300 overflows the right-hand side).
      RequireFinite(irradiance, "the boundary irradiance", OverflowCause());
      RequireFinite(fluence, "Fluence (" + SolverName_ + " solver)", OverflowCause());
    }
  }
  catch (...)
  {
    Solver_->Reset();
    throw;
  }
  if (!solved)
  {
    return false; // aborted by the progress callback
  }
  if (vertex && IncrementalAssembly_)
  {
    LastMaterial_ = std::move(material);
    LastIrradiance_ = std::move(irradiance);
    HaveLast_ = true;
  }
  return true;
}

} // namespace translucency
