#include "VertexDiffusionSolver.h"

#include "Error.h"
#include "TetMesh.h"

#include <chrono>

namespace translucency
{

namespace
{
double Since(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
    .count();
}
}

VertexDiffusionSolver::VertexDiffusionSolver(std::unique_ptr<Discretization> discretization)
  : Discretization_(std::move(discretization))
{
}

void VertexDiffusionSolver::Reset()
{
  for (auto& x : Solution_)
  {
    x.resize(0);
  }
  LastMesh_ = nullptr;
  LastPoints_ = -1;
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
  report.LinearSolver = "cg-jacobi";

  auto start = std::chrono::steady_clock::now();
  // Painting: rebuild only the rows of the changed tets' vertices (TransCut
  // Sec. 5.2) when the system of the last successful solve is of this mesh.
  // The request is one-shot, also when the update throws.
  const bool requested = HasChangedTets_;
  std::vector<int> changedTets;
  changedTets.swap(ChangedTets_);
  HasChangedTets_ = false;
  const bool incremental = requested && LastMesh_ == &mesh &&
    LastPoints_ == mesh.GetNumberOfPoints() && LastRevision_ == mesh.GetGeometryRevision() &&
    Discretization_->UpdateTets(mesh, *problem.Material, *problem.Irradiance, changedTets, System_);
  if (!incremental)
  {
    Discretization_->Assemble(mesh, *problem.Material, *problem.Irradiance, System_);
  }
  report.Assembly = incremental ? "incremental" : "full";
  report.SetupMilliseconds = Since(start);

  // A warm start needs the same unknowns: the same mesh object and size.
  const bool sameUnknowns = LastMesh_ == &mesh && LastPoints_ == mesh.GetNumberOfPoints();
  if (!sameUnknowns)
  {
    Reset();
  }
  start = std::chrono::steady_clock::now();
  Solver_.SetRelTol(RelTol_);
  Solver_.SetMaxIter(MaxIter_);
  Solver_.SetProgressCallback([this](double f) { return ReportProgress(f); });
  if (!Solver_.Solve(System_, Solution_, WarmStart_ && sameUnknowns))
  {
    Reset();
    return false;
  }
  LastMesh_ = &mesh;
  LastPoints_ = mesh.GetNumberOfPoints();
  LastRevision_ = mesh.GetGeometryRevision();
  report.SolveMilliseconds = Since(start);

  report.NumberOfUnknowns = System_.NumberOfUnknowns;
  report.NumberOfNonZeros = static_cast<long long>(System_.ColumnIndices.size());
  report.MemoryBytes = System_.RowOffsets.size() * sizeof(int) +
    System_.ColumnIndices.size() * sizeof(int) +
    NumberOfChannels * System_.ColumnIndices.size() * sizeof(double) +
    2 * NumberOfChannels * static_cast<std::size_t>(System_.NumberOfUnknowns) * sizeof(double);
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    report.Iterations[c] = Solver_.GetNumIterations(c);
    report.Residual[c] = Solver_.GetFinalNorm(c);
    report.Converged[c] = Solver_.GetConverged(c);
  }
  Discretization_->ToPointFluence(mesh, System_, Solution_, fluence);
  return true;
}

} // namespace translucency
