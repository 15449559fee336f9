#include "VertexDiffusionSolver.h"

#include "ComplexConjugateGradient.h"
#include "Error.h"
#include "Strings.h"
#include "TetMesh.h"
#include "Timer.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <complex>
#include <functional>
#include <iomanip>
#include <limits>
#include <sstream>

namespace translucency
{

namespace
{

/// The speed of light in vacuum, mm/s.
constexpr double SpeedOfLight = 299792458e3;

/// b += 4 x the source load (the discretisations' matrices and right-hand
/// sides are 4 x the weak form's; the load is the weak form's, in W).
void AddSourceLoad(const std::vector<double>& load, DiffusionSystem& system)
{
  const int n = system.NumberOfUnknowns;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    for (int i = 0; i < n; ++i)
    {
      system.RightHandSide[c][i] += 4.0 * load[3 * static_cast<std::size_t>(i) + c];
    }
  }
}

/// Solve: the load of the interior sources and, with the extended
/// collimated model, of the beam's volume source (`collimated` gets the
/// beam, from `cache`: a paint re-integrates the changed tets only); empty
/// without either.
std::vector<double> SourceLoad(const DiffusionProblem& problem, bool extended,
  CollimatedSourceCache& cache, CollimatedSource& collimated)
{
  const TetMesh& mesh = *problem.Mesh;
  std::vector<double> sourceLoad;
  if (problem.HasInteriorSources())
  {
    sourceLoad = problem.InteriorSources->ComputeLoad(mesh, *problem.Material);
  }
  if (extended)
  {
    collimated = cache.Compute(mesh, *problem.Material, problem.Lights, problem.Shadows);
    if (sourceLoad.empty())
    {
      sourceLoad.swap(collimated.Load);
    }
    else
    {
      for (std::size_t k = 0; k < sourceLoad.size(); ++k)
      {
        sourceLoad[k] += collimated.Load[k];
      }
    }
  }
  return sourceLoad;
}

/// Solve: the linear solver's set-up for `system`: a rebuild for a new
/// solver object, mesh or moved points (`rebuild`: the hierarchy's eq. 16
/// weights depend on edge lengths), else values only when they changed
/// (only the changed tets' rows after an incremental update), else none
/// (relight). Returns what was done, for SolverReport::LinearSetup.
const char* SetUpLinearSolver(LinearSolver& linear, const DiffusionSystem& system,
  const TetMesh& mesh, bool rebuild, bool incremental, const std::vector<int>& changedTets,
  const std::array<std::vector<double>, NumberOfChannels>& previousValues)
{
  if (rebuild)
  {
    // New solver object, new mesh or moved points (the hierarchy's eq. 16
    // weights depend on edge lengths): rebuild everything.
    linear.Setup(system, &mesh, true);
    return "rebuilt";
  }
  bool valuesChanged = incremental && !changedTets.empty();
  for (int c = 0; !incremental && c < NumberOfChannels && !valuesChanged; ++c)
  {
    valuesChanged = system.Values[c] != previousValues[c];
  }
  if (valuesChanged && incremental)
  {
    // Only the rows of the changed tets' vertices changed.
    const std::vector<int>& tets = mesh.GetTets();
    std::vector<int> rows;
    rows.reserve(4 * changedTets.size());
    for (const int t : changedTets)
    {
      for (int v = 0; v < 4; ++v)
      {
        rows.push_back(tets[4 * static_cast<std::size_t>(t) + v]);
      }
    }
    linear.SetupChangedRows(system, &mesh, rows);
    return "rows";
  }
  if (valuesChanged)
  {
    linear.Setup(system, &mesh, false); // same pattern, new values
    return "values";
  }
  // Otherwise only the right-hand side changed (relight): no Setup.
  return "kept";
}

/// SolveFrequencyDomain, the extended collimated model: the beam's volume
/// source carries its own modulation exp(-i omega eta s / c)
/// (CollimatedSource.h): a complex right-hand side, 4 x the load as for the
/// interior sources, its real part added to `system`'s right-hand sides and
/// its imaginary part in `imaginaryRight`; the beam in `collimated` and its
/// complex fluence in `collimatedFluence`.
void AddCollimatedFrequencyLoad(const DiffusionProblem& problem, double omega,
  DiffusionSystem& system, CollimatedSource& collimated,
  std::vector<std::complex<double>>& collimatedFluence,
  std::array<Eigen::VectorXd, NumberOfChannels>& imaginaryRight)
{
  const TetMesh& mesh = *problem.Mesh;
  const OpticalProperties& material = *problem.Material;
  collimated = ComputeCollimatedSource(mesh, material, problem.Lights, problem.Shadows);
  std::vector<std::complex<double>> load;
  ComputeCollimatedFrequencyLoad(
    mesh, material, collimated, omega / SpeedOfLight, load, collimatedFluence);
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    imaginaryRight[c].setZero(system.NumberOfUnknowns);
    for (int i = 0; i < system.NumberOfUnknowns; ++i)
    {
      const std::complex<double> value = 4.0 * load[3 * static_cast<std::size_t>(i) + c];
      system.RightHandSide[c][i] += value.real();
      imaginaryRight[c][i] = value.imag();
    }
  }
}

/// SolveFrequencyDomain: the imaginary part of the matrix, the mass matrix
/// of the imaginary absorption omega eta_t / c (1/mm) per tet and channel,
/// on the system's pattern; false if the discretisation has none.
bool ImaginaryMass(Discretization& discretization, const TetMesh& mesh,
  const OpticalProperties& material, double omega, const DiffusionSystem& system,
  std::array<std::vector<double>, NumberOfChannels>& imaginary)
{
  const int numTets = mesh.GetNumberOfTets();
  std::vector<double> coefficient(3 * static_cast<std::size_t>(numTets));
  for (int t = 0; t < numTets; ++t)
  {
    const double value = omega * material.RefractiveIndex[t] / SpeedOfLight;
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      coefficient[3 * static_cast<std::size_t>(t) + c] = value;
    }
  }
  for (auto& values : imaginary)
  {
    values.assign(system.ColumnIndices.size(), 0.0);
  }
  return discretization.AddMass(mesh, coefficient, imaginary);
}

/// SolveFrequencyDomain's preconditioner: the cycle of the linear solver
/// `name` (the one this solve would use in continuous wave: by name, or by
/// size multigrid-agg from LargeSystemUnknowns on), built on the real part
/// A, when that solver has one (LinearSolver::HasPreconditioner); else null
/// (Jacobi). Documentation/DiffuseOptics.md says why.
std::unique_ptr<LinearSolver> RealPartPreconditioner(
  const std::string& name, const DiffusionSystem& system, const TetMesh& mesh)
{
  std::unique_ptr<LinearSolver> real = CreateLinearSolver(name); // throws, listing the known names
  // Only solvers with a cycle are set up (a factorisation would be wasted).
  if (real->GetName() == "multigrid-agg")
  {
    real->Setup(system, &mesh, true);
  }
  if (!real->HasPreconditioner())
  {
    real.reset();
  }
  return real;
}

/// SolveFrequencyDomain without a cycle of the real part: COCG with Jacobi,
/// channel by channel (the imaginary right-hand sides with `extended`);
/// false if `progress` (the fraction done) aborted.
bool SolveChannelsJacobiCOCG(const DiffusionSystem& system,
  const std::array<std::vector<double>, NumberOfChannels>& imaginary, bool extended,
  const std::array<Eigen::VectorXd, NumberOfChannels>& imaginaryRight, double relTol,
  int maxIter, const std::function<bool(double)>& progress,
  std::array<Eigen::VectorXd, NumberOfChannels>& realPart,
  std::array<Eigen::VectorXd, NumberOfChannels>& imagPart, SolverReport& report)
{
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    Eigen::VectorXcd x;
    LinearSolveStats stats;
    const auto channelProgress = [&progress, maxIter, c](int iteration) {
      return progress((c + static_cast<double>(iteration) / std::max(1, maxIter)) /
        NumberOfChannels);
    };
    Eigen::VectorXcd b = system.RightHandSide[c].cast<std::complex<double>>();
    if (extended)
    {
      b.imag() = imaginaryRight[c];
    }
    if (!SolveComplexSymmetricCOCG(system.NumberOfUnknowns, system.RowOffsets.data(),
          system.ColumnIndices.data(), system.Values[c].data(), imaginary[c].data(), b, x,
          relTol, maxIter, stats, channelProgress))
    {
      return false;
    }
    realPart[c] = x.real();
    imagPart[c] = x.imag();
    report.Iterations[c] = stats.Iterations;
    report.Residual[c] = stats.RelativeResidual;
    report.Converged[c] = stats.Converged;
  }
  return true;
}

} // namespace

VertexDiffusionSolver::VertexDiffusionSolver(std::unique_ptr<Discretization> discretization)
  : Discretization_(std::move(discretization))
{
}

std::string VertexDiffusionSolver::GetDefaultLinearSolverName()
{
  return "cg-jacobi";
}

std::string VertexDiffusionSolver::GetDefaultLinearSolverName(int unknowns)
{
  return unknowns < LargeSystemUnknowns ? GetDefaultLinearSolverName() : "multigrid-agg";
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
  IrradianceChanged_ = false;
  ChangedTets_.clear();
}

void VertexDiffusionSolver::SetChangedTets(std::vector<int> changedTets, bool irradianceChanged)
{
  ChangedTets_ = std::move(changedTets);
  HasChangedTets_ = true;
  IrradianceChanged_ = irradianceChanged;
}

namespace
{
/// The size, memory and per-channel convergence of a solve, for its report.
void ReportSolve(const DiffusionSystem& system, const LinearSolver& linear,
  const std::array<LinearSolveStats, NumberOfChannels>& stats, SolverReport& report)
{
  report.NumberOfUnknowns = system.NumberOfUnknowns;
  report.NumberOfNonZeros = static_cast<long long>(system.ColumnIndices.size());
  report.MemoryBytes = system.RowOffsets.size() * sizeof(int) +
    system.ColumnIndices.size() * sizeof(int) +
    NumberOfChannels * system.ColumnIndices.size() * sizeof(double) +
    2 * NumberOfChannels * static_cast<std::size_t>(system.NumberOfUnknowns) * sizeof(double) +
    linear.GetMemoryBytes();
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    report.Iterations[c] = stats[c].Iterations;
    report.Residual[c] = stats[c].RelativeResidual;
    report.Converged[c] = stats[c].Converged;
    report.StoppedByChange[c] = stats[c].StoppedByChange;
  }
}
} // namespace

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
  std::string name = LinearSolver_.empty()
    ? GetDefaultLinearSolverName(mesh.GetNumberOfPoints())
    : LinearSolver_;
  name = ToLower(name);
  if (!Linear_ || name != LinearName_)
  {
    Linear_ = CreateLinearSolver(name); // throws, listing the known names
    LinearName_ = name;
    LinearReady_ = false;
  }
  report.LinearSolver = Linear_->GetName();

  auto start = Clock::now();
  // Interior sources: their load, computed first (a source outside the
  // object is an error before any work).
  // The extended collimated model adds its volume source to the same load.
  const bool extended = IsExtendedCollimatedModel(problem.Collimated);
  // The Robin coefficients of this problem (the moment rule with
  // ExtendedMoments): a change of rule changes every boundary row.
  const Fresnel::BoundaryRule rule = problem.Collimated == CollimatedModel::ExtendedMoments
    ? Fresnel::BoundaryRule::Moments
    : Fresnel::BoundaryRule::Fit;
  const bool sameRule = rule == Discretization_->GetBoundaryRule();
  Discretization_->SetBoundaryRule(rule);
  const bool hasSources = problem.HasInteriorSources() || extended;
  CollimatedSource collimated;
  const std::vector<double> sourceLoad =
    SourceLoad(problem, extended, CollimatedCache_, collimated);
  report.Collimated = extended ? CollimatedCache_.GetLastUpdate() : "";
  // Painting: rebuild only the rows of the changed tets' vertices (TransCut
  // Sec. 5.2) when the system of the last successful solve is of this mesh
  // with its current geometry. The request is one-shot, also when the update
  // throws.
  const bool requested = HasChangedTets_;
  const bool newIrradiance = IrradianceChanged_;
  std::vector<int> changedTets;
  changedTets.swap(ChangedTets_);
  HasChangedTets_ = false;
  IrradianceChanged_ = false;
  const bool sameGeometry = LastMesh_ == &mesh && LastPoints_ == mesh.GetNumberOfPoints() &&
    LastTets_ == mesh.GetNumberOfTets() && LastRevision_ == mesh.GetGeometryRevision();
  // The incremental update rebuilds right-hand-side rows from q only. A
  // relight rebuilds the right-hand side (before UpdateTets, which leaves
  // System_ alone when it returns false: nothing is half updated). With a
  // volume load in this or the last system (interior sources, the extended
  // collimated beam) the kept right-hand side holds the last load: it is
  // rebuilt from q (interior rows 0, as Assemble leaves them) and the new
  // load is added below, so the system equals a full assembly's bit for bit
  // while the matrices and the linear solver's set-up are kept.
  const bool canUpdate = requested && sameGeometry && sameRule && LinearReady_;
  const bool rebuildRight = newIrradiance || hasSources || SystemHasSources_;
  if (canUpdate && rebuildRight && (hasSources || SystemHasSources_))
  {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      std::fill(System_.RightHandSide[c].begin(), System_.RightHandSide[c].end(), 0.0);
    }
  }
  const bool incremental = canUpdate &&
    (!rebuildRight ||
      Discretization_->UpdateRightHandSide(mesh, *problem.Material, *problem.Irradiance, System_)) &&
    (changedTets.empty() ||
      Discretization_->UpdateTets(mesh, *problem.Material, *problem.Irradiance, changedTets, System_));
  if (!incremental)
  {
    // Keep the previous values (swap, no copy) to see whether they changed.
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      PreviousValues_[c].swap(System_.Values[c]);
    }
    Discretization_->Assemble(mesh, *problem.Material, *problem.Irradiance, System_);
  }
  report.Assembly = !incremental ? "full"
    : rebuildRight && changedTets.empty() ? "right-hand side"
                                          : "incremental";
  SystemHasSources_ = hasSources;
  if (hasSources)
  {
    AddSourceLoad(sourceLoad, System_);
  }

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
  // The interactive rule watches the boundary fluence (what a picture shows).
  Linear_->SetChangeRule(
    ChangeTol_, ChangeTol_ > 0.0 ? mesh.GetBoundaryPoints() : std::vector<int>());
  Linear_->SetProgressCallback([this](double f) { return ReportProgress(f); });
  report.LinearSetup = SetUpLinearSolver(*Linear_, System_, mesh, !LinearReady_ || !sameGeometry,
    incremental, changedTets, PreviousValues_);
  LinearReady_ = true;
  report.SetupMilliseconds = MillisecondsSince(start);
  // When the matrix values changed on the same mesh (a paint stroke), the
  // warm start iterates at least once: a stroke on 1 % of the tets can move
  // the global relative residual by less than a loose RelTol while the
  // fluence under it is still the unpainted one (Documentation/Solvers.md,
  // "The interactive stopping rule").
  Linear_->SetMinIter(
    report.LinearSetup == "rows" || report.LinearSetup == "values" ? 1 : 0);

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

  ReportSolve(System_, *Linear_, stats, report);
  Discretization_->ToPointFluence(mesh, System_, Solution_, fluence);
  if (extended)
  {
    AddCollimatedFluence(collimated, fluence, report);
  }
  return true;
}

void VertexDiffusionSolver::CheckFrequencyResolution(const TetMesh& mesh,
  const OpticalProperties& material, double frequency, double omega) const
{
  translucency::CheckFrequencyResolution(GetName(), mesh, material, frequency, omega);
}

void CheckFrequencyResolution(const std::string& name, const TetMesh& mesh,
  const OpticalProperties& material, double frequency, double omega)
{
  // The diffusion wave exp(-k r), k = sqrt((mu_a + i omega eta / c) / kappa)
  // per tet and channel, oscillates with the wavelength 2 pi / Im k. A mesh
  // whose edges are longer than the shortest wavelength cannot carry its
  // phase (and omega eta / c overflows for absurd frequencies): refused with
  // both lengths, not solved into nonsense or NaN.
  const int numTets = mesh.GetNumberOfTets();
  double volume = 0.0;
  for (double v : mesh.GetTetVolumes())
  {
    volume += v;
  }
  // The edge of a regular tet of the mean volume (V = a^3 / (6 sqrt 2)).
  const double edge = std::cbrt(6.0 * std::sqrt(2.0) * volume / std::max(numTets, 1));
  double shortest = std::numeric_limits<double>::infinity();
  bool finite = true;
  for (int t = 0; t < numTets && finite; ++t)
  {
    const double q = omega * material.RefractiveIndex[t] / SpeedOfLight; // 1/mm
    finite = std::isfinite(q);
    for (int c = 0; c < NumberOfChannels && finite; ++c)
    {
      const std::size_t i = 3 * static_cast<std::size_t>(t) + c;
      const double attenuation =
        material.AbsorptionCoefficient[i] + material.ReducedScatteringCoefficient[i];
      if (!(attenuation > 0.0))
      {
        continue;
      }
      const double kappa = 1.0 / (3.0 * attenuation);
      const std::complex<double> k =
        std::sqrt(std::complex<double>(material.AbsorptionCoefficient[i], q) / kappa);
      finite = std::isfinite(k.imag());
      if (finite && k.imag() > 0.0)
      {
        shortest = std::min(shortest, 2.0 * 3.14159265358979323846 / k.imag());
      }
    }
  }
  if (!finite || shortest < edge)
  {
    std::ostringstream out;
    out << std::setprecision(4) << name << ": modulation frequency " << frequency << " Hz: ";
    if (!finite)
    {
      out << "omega eta / c overflows (not finite)";
    }
    else
    {
      out << "the diffusion wave's shortest wavelength in the medium, " << shortest
          << " mm, is below the mesh's typical edge, " << edge
          << " mm: the mesh cannot resolve its phase";
    }
    out << " (use a lower frequency or a finer mesh)";
    throw Error(out.str());
  }
}

bool VertexDiffusionSolver::SolveFrequencyDomain(const DiffusionProblem& problem,
  double frequency, std::vector<std::complex<double>>& fluence, SolverReport& report)
{
  if (!problem.Mesh || !problem.Material || !problem.Irradiance)
  {
    throw Error(GetName() + ": the problem needs a mesh, a material and an irradiance");
  }
  if (!std::isfinite(frequency) || !(frequency > 0.0))
  {
    std::ostringstream out;
    out << GetName() << ": modulation frequency " << frequency
        << " Hz (expected a finite value > 0; 0 is the continuous-wave Solve())";
    throw Error(out.str());
  }
  const TetMesh& mesh = *problem.Mesh;
  const OpticalProperties& material = *problem.Material;
  report = SolverReport();
  report.Solver = GetName();
  report.Assembly = "full";

  auto start = Clock::now();
  std::vector<double> sourceLoad;
  if (problem.HasInteriorSources())
  {
    sourceLoad = problem.InteriorSources->ComputeLoad(mesh, material);
  }
  DiffusionSystem system;
  // The Robin coefficients of the model (the Fresnel moments with
  // extended-moments), whatever the last continuous-wave solve used.
  Discretization_->SetBoundaryRule(problem.Collimated == CollimatedModel::ExtendedMoments
      ? Fresnel::BoundaryRule::Moments
      : Fresnel::BoundaryRule::Fit);
  Discretization_->Assemble(mesh, material, *problem.Irradiance, system);
  if (!sourceLoad.empty())
  {
    AddSourceLoad(sourceLoad, system);
  }
  const double omega = 2.0 * 3.14159265358979323846 * frequency;
  CheckFrequencyResolution(mesh, material, frequency, omega);
  // The extended collimated model: the beam's volume source carries its
  // own modulation exp(-i omega eta s / c) (CollimatedSource.h): a complex
  // right-hand side, 4 x the load as for the interior sources.
  const bool extended = IsExtendedCollimatedModel(problem.Collimated);
  CollimatedSource collimated;
  std::vector<std::complex<double>> collimatedFluence;
  std::array<Eigen::VectorXd, NumberOfChannels> imaginaryRight;
  if (extended)
  {
    AddCollimatedFrequencyLoad(
      problem, omega, system, collimated, collimatedFluence, imaginaryRight);
  }
  // The imaginary absorption omega eta_t / c (1/mm) per tet and channel.
  std::array<std::vector<double>, NumberOfChannels> imaginary;
  if (!ImaginaryMass(*Discretization_, mesh, material, omega, system, imaginary))
  {
    throw Error(GetName() + ": this discretisation has no frequency-domain solve");
  }

  // The preconditioner: the cycle of the linear solver this solve would use
  // in continuous wave, built on the real part A, or Jacobi (null).
  const std::string name = ToLower(LinearSolver_.empty()
      ? GetDefaultLinearSolverName(mesh.GetNumberOfPoints())
      : LinearSolver_);
  std::unique_ptr<LinearSolver> real = RealPartPreconditioner(name, system, mesh);
  report.LinearSolver = real ? "cocg-" + real->GetName() : "cocg-jacobi";
  report.SetupMilliseconds = MillisecondsSince(start);

  start = Clock::now();
  std::array<Eigen::VectorXd, NumberOfChannels> realPart, imagPart;
  if (real)
  {
    std::array<Eigen::VectorXcd, NumberOfChannels> x;
    std::array<LinearSolveStats, NumberOfChannels> stats;
    const auto progress = [this](int iteration) {
      return ReportProgress(static_cast<double>(iteration) / std::max(1, MaxIter_));
    };
    const LinearSolver* preconditioner = real.get();
    if (!SolveComplexSymmetricBlockedCOCG(system, imaginary,
          [preconditioner](const double* r, double* z) {
            preconditioner->ApplyPreconditioner(r, z);
          },
          x, RelTol_, MaxIter_, stats, progress, extended ? &imaginaryRight : nullptr))
    {
      return false;
    }
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      realPart[c] = x[c].real();
      imagPart[c] = x[c].imag();
      report.Iterations[c] = stats[c].Iterations;
      report.Residual[c] = stats[c].RelativeResidual;
      report.Converged[c] = stats[c].Converged;
    }
  }
  if (!real &&
    !SolveChannelsJacobiCOCG(system, imaginary, extended, imaginaryRight, RelTol_, MaxIter_,
      [this](double fraction) { return ReportProgress(fraction); }, realPart, imagPart, report))
  {
    return false;
  }
  report.SolveMilliseconds = MillisecondsSince(start);
  report.NumberOfUnknowns = system.NumberOfUnknowns;
  report.NumberOfNonZeros = static_cast<long long>(system.ColumnIndices.size());
  // The system, the imaginary mass values, COCG's complex work vectors and
  // the preconditioner's hierarchy.
  report.MemoryBytes = system.GetMemoryBytes() +
    NumberOfChannels * system.ColumnIndices.size() * sizeof(double) +
    (real ? 36 : 10) * static_cast<std::size_t>(system.NumberOfUnknowns) * sizeof(double) +
    (real ? real->GetMemoryBytes() : 0);
  std::vector<double> re, im;
  Discretization_->ToPointFluence(mesh, system, realPart, re);
  Discretization_->ToPointFluence(mesh, system, imagPart, im);
  fluence.resize(re.size());
  for (std::size_t i = 0; i < re.size(); ++i)
  {
    fluence[i] = std::complex<double>(re[i], im[i]);
  }
  if (extended)
  {
    AddCollimatedFluence(collimated, collimatedFluence, fluence, report);
  }
  return true;
}

} // namespace translucency
