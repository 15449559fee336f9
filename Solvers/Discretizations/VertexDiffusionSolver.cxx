#include "VertexDiffusionSolver.h"

#include "Error.h"
#include "Strings.h"
#include "TetMesh.h"
#include "Timer.h"

#include <algorithm>
#include <cctype>

namespace translucency
{

VertexDiffusionSolver::VertexDiffusionSolver(std::unique_ptr<Discretization> discretization)
  : Discretization_(std::move(discretization))
{
}

std::string VertexDiffusionSolver::GetDefaultLinearSolverName()
{
  return "cg-jacobi";
}

void VertexDiffusionSolver::Reset()
{
  for (auto& x : Solution_)
  {
    x.resize(0);
  }
  LastMesh_ = nullptr;
  LastPoints_ = -1;
  LastTets_ = -1;
  LastNonZeros_ = 0;
  LinearReady_ = false;
  LastRevision_ = 0;
  HasChangedTets_ = false;
  ChangedTets_.clear();
}

void VertexDiffusionSolver::SetChangedTets(std::vector<int> changedTets)
{
  ChangedTets_ = std::move(changedTets);
  HasChangedTets_ = true;
}

bool VertexDiffusionSolver::Solve(
  const DiffusionProblem& problem, std::vector<double>& fluence, SolverReport& report)
{
  if (!problem.Mesh || !problem.Material || !problem.Irradiance)
  {
    throw Error(GetName() + ": the problem needs a mesh, a material and an irradiance");
  }
  const TetMesh& mesh = *problem.Mesh;
  report = SolverReport();
  report.Solver = GetName();

  // The linear solver by name (kept while the name stays the same).
  std::string name = LinearSolver_.empty() ? GetDefaultLinearSolverName() : LinearSolver_;
  name = ToLower(name);
  if (!Linear_ || name != LinearName_)
  {
    Linear_ = CreateLinearSolver(name); // throws, listing the known names
    LinearName_ = name;
    LinearReady_ = false;
  }
  report.LinearSolver = Linear_->GetName();

  auto start = Clock::now();
  // Painting: rebuild only the rows of the changed tets' vertices (TransCut
  // Sec. 5.2) when the system of the last successful solve is of this mesh
  // with its current geometry. The request is one-shot, also when the update
  // throws.
  const bool requested = HasChangedTets_;
  std::vector<int> changedTets;
  changedTets.swap(ChangedTets_);
  HasChangedTets_ = false;
  const bool sameGeometry = LastMesh_ == &mesh && LastPoints_ == mesh.GetNumberOfPoints() &&
    LastTets_ == mesh.GetNumberOfTets() && LastRevision_ == mesh.GetGeometryRevision();
  const bool incremental = requested && sameGeometry && LinearReady_ &&
    Discretization_->UpdateTets(mesh, *problem.Material, *problem.Irradiance, changedTets, System_);
  if (!incremental)
  {
    // Keep the previous values (swap, no copy) to see whether they changed.
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      PreviousValues_[c].swap(System_.Values[c]);
    }
    Discretization_->Assemble(mesh, *problem.Material, *problem.Irradiance, System_);
  }
  report.Assembly = incremental ? "incremental" : "full";

  // A warm start needs the same unknowns: the same mesh object and size;
  // the same tets and pattern size, or the linear solver is set up anew.
  const bool sameUnknowns = LastMesh_ == &mesh && LastPoints_ == mesh.GetNumberOfPoints() &&
    LastTets_ == mesh.GetNumberOfTets() && LastNonZeros_ == System_.ColumnIndices.size();
  if (!sameUnknowns)
  {
    Reset();
  }
  Linear_->SetRelTol(RelTol_);
  Linear_->SetMaxIter(MaxIter_);
  Linear_->SetProgressCallback([this](double f) { return ReportProgress(f); });
  if (!LinearReady_ || !sameGeometry)
  {
    // New solver object, new mesh or moved points (the hierarchy's eq. 16
    // weights depend on edge lengths): rebuild everything.
    Linear_->Setup(System_, &mesh, true);
  }
  else
  {
    bool valuesChanged = incremental && !changedTets.empty();
    for (int c = 0; !incremental && c < NumberOfChannels && !valuesChanged; ++c)
    {
      valuesChanged = System_.Values[c] != PreviousValues_[c];
    }
    if (valuesChanged)
    {
      Linear_->Setup(System_, &mesh, false); // same pattern, new values
    }
    // Otherwise only the right-hand side changed (relight): no Setup.
  }
  LinearReady_ = true;
  report.SetupMilliseconds = MillisecondsSince(start);

  start = Clock::now();
  std::array<LinearSolveStats, NumberOfChannels> stats;
  if (!Linear_->Solve(System_, Solution_, WarmStart_ && sameUnknowns, stats))
  {
    Reset();
    return false;
  }
  LastMesh_ = &mesh;
  LastPoints_ = mesh.GetNumberOfPoints();
  LastTets_ = mesh.GetNumberOfTets();
  LastNonZeros_ = System_.ColumnIndices.size();
  LastRevision_ = mesh.GetGeometryRevision();
  report.SolveMilliseconds = MillisecondsSince(start);

  report.NumberOfUnknowns = System_.NumberOfUnknowns;
  report.NumberOfNonZeros = static_cast<long long>(System_.ColumnIndices.size());
  report.MemoryBytes = System_.RowOffsets.size() * sizeof(int) +
    System_.ColumnIndices.size() * sizeof(int) +
    NumberOfChannels * System_.ColumnIndices.size() * sizeof(double) +
    2 * NumberOfChannels * static_cast<std::size_t>(System_.NumberOfUnknowns) * sizeof(double) +
    Linear_->GetMemoryBytes();
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    report.Iterations[c] = stats[c].Iterations;
    report.Residual[c] = stats[c].RelativeResidual;
    report.Converged[c] = stats[c].Converged;
  }
  Discretization_->ToPointFluence(mesh, System_, Solution_, fluence);
  return true;
}

} // namespace translucency
