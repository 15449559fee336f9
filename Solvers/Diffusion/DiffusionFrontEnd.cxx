#include "DiffusionFrontEnd.h"
#include "ResourceLimits.h"

#include "DiffusionSolverFactory.h"
#include "TetMesh.h"
#include "Strings.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstring>
#include <sstream>

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
  Solver_ = MakeSolver(entry.Name, Comm_);
  SolverName_ = entry.Name;
  ForgetLast();
}

std::unique_ptr<DiffusionSolver> DiffusionFrontEnd::MakeSolver(
  const std::string& name, const Communicator& comm)
{
  if (!comm.IsMPI())
  {
    return CreateDiffusionSolver(name);
  }
  // Chosen by the registry trait Distributed (the Parallel layer registers
  // the variants it has), never by name or type.
  std::unique_ptr<DiffusionSolver> solver = CreateDistributedDiffusionSolver(name);
  solver->SetCommunicator(comm);
  return solver;
}

void DiffusionFrontEnd::SetCommunicator(const Communicator& comm)
{
  if (Solver_ && comm.GetHandle() == Comm_.GetHandle() && comm.GetSize() == Comm_.GetSize())
  {
    return;
  }
  Solver_ = MakeSolver(SolverName_, comm); // throws before anything changes
  Comm_ = comm;
  Mesh_.reset();
  ChangedTets_ = -1;
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
  PendingChanges_.reset();
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

void DiffusionFrontEnd::CheckDomain(const SolveRequest& request) const
{
  const DiffusionSolverTraits& traits = GetDiffusionSolverRegistry().Get(SolverName_).Properties;
  if (request.Domain == SolveDomain::Frequency && !traits.SupportsFrequency)
  {
    throw Error("the " + SolverName_ + " solver has no frequency domain (modulation frequency " +
      FormatNumber(request.Frequency) + " Hz): solvers with one: " +
      JoinNames(GetDiffusionSolverNamesWith(DiffusionTrait::Frequency)));
  }
  if (request.Domain == SolveDomain::Time && !traits.SupportsTime)
  {
    throw Error("the " + SolverName_ +
      " solver has no frequency domain or time gates: time gates are implemented by " +
      JoinNames(GetDiffusionSolverNamesWith(DiffusionTrait::Time)) +
      ", the frequency domain by " +
      JoinNames(GetDiffusionSolverNamesWith(DiffusionTrait::Frequency)));
  }
  // A replicated variant (the Monte Carlo's photons split over the ranks)
  // has the whole problem on every rank: its time gates are its own.
  if (Comm_.IsMPI() && !traits.Replicated && request.Domain != SolveDomain::ContinuousWave)
  {
    throw Error("the distributed " + SolverName_ +
      " solve is continuous wave only: the frequency domain and time gates are solved in one "
      "process");
  }
  if (request.Domain != SolveDomain::Time && !request.Snapshots.empty())
  {
    throw Error("time snapshots without time gates");
  }
}

void DiffusionFrontEnd::DetectChangedTets(
  const OpticalProperties& material, const std::vector<double>& irradiance, bool kept)
{
  // Same mesh (topology and points), only some tets' coefficients changed
  // since the last successful solve: found by comparing with the
  // coefficients cached from that solve (none when the caller passed the
  // kept material back: `kept`). Another irradiance (a relight) rebuilds the
  // right-hand side too.
  const std::size_t numTets = material.RefractiveIndex.size();
  const auto limit = static_cast<std::size_t>(MaximumChangedFraction_ * numTets);
  if (kept && IncrementalAssembly_ && LastIrradiance_.size() == irradiance.size())
  {
    const bool relit = std::memcmp(LastIrradiance_.data(), irradiance.data(),
                         irradiance.size() * sizeof(double)) != 0;
    if (PendingChanges_)
    {
      // UpdateKeptMaterial wrote a paint stroke into the kept material;
      // more than the limit: a full assembly.
      std::vector<int> changed = std::move(*PendingChanges_);
      PendingChanges_.reset();
      if (changed.size() <= limit)
      {
        ChangedTets_ = static_cast<long long>(changed.size());
        Solver_->SetChangedTets(std::move(changed), relit);
      }
      return;
    }
    ChangedTets_ = 0;
    Solver_->SetChangedTets(std::vector<int>(), relit);
    return;
  }
  if (!kept && IncrementalAssembly_ && HaveLast_ && LastMaterial_.RefractiveIndex.size() == numTets &&
    LastMaterial_.AbsorptionCoefficient.size() == material.AbsorptionCoefficient.size() &&
    LastMaterial_.ReducedScatteringCoefficient.size() ==
      material.ReducedScatteringCoefficient.size() &&
    LastIrradiance_.size() == irradiance.size())
  {
    const bool relit = std::memcmp(LastIrradiance_.data(), irradiance.data(),
                         irradiance.size() * sizeof(double)) != 0;
    ++MaterialComparisons_;
    std::vector<int> changed = FindChangedTets(LastMaterial_, material, limit);
    if (changed.size() <= limit)
    {
      ChangedTets_ = static_cast<long long>(changed.size());
      Solver_->SetChangedTets(std::move(changed), relit);
    }
  }
}

bool DiffusionFrontEnd::Solve(std::shared_ptr<const TetMesh> mesh, OpticalProperties material,
  std::vector<double> irradiance, const DiffusionProblem& light, std::vector<double>& fluence,
  SolverReport& report)
{
  SolveResult result;
  if (!Solve(std::move(mesh), std::move(material), std::move(irradiance), light, SolveRequest(),
        result))
  {
    return false;
  }
  fluence = std::move(result.Fluence);
  report = std::move(result.Report);
  return true;
}

namespace
{
/// "channel G: relative residual 0.66 after 1 iterations; ..." for the
/// channels that did not converge ("" if all did).
std::string UnconvergedChannels(const SolverReport& report)
{
  static const char* names[NumberOfChannels] = { "R", "G", "B" };
  std::string text;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    if (!report.Converged[c] && report.Iterations[c] > 0)
    {
      text += std::string(text.empty() ? "" : "; ") + "channel " + names[c] +
        ": relative residual " + FormatNumber(report.Residual[c]) + " after " +
        std::to_string(report.Iterations[c]) + " iterations";
    }
  }
  return text;
}
}

bool DiffusionFrontEnd::HasKeptMaterial(const std::shared_ptr<const TetMesh>& mesh) const
{
  return HaveLast_ && mesh && mesh == Mesh_ &&
    LastMaterial_.RefractiveIndex.size() == static_cast<std::size_t>(mesh->GetNumberOfTets());
}

bool DiffusionFrontEnd::UpdateKeptMaterial(const std::shared_ptr<const TetMesh>& mesh,
  const double* absorption, const double* scattering, const double* refractiveIndex)
{
  if (!HasKeptMaterial(mesh) || !absorption || !scattering || !refractiveIndex)
  {
    return false;
  }
  ++MaterialComparisons_;
  OpticalProperties& kept = LastMaterial_;
  const long long numTets = static_cast<long long>(kept.RefractiveIndex.size());
  // Fixed chunks (not per thread): the changed tets come out in order at any
  // thread count.
  constexpr long long chunk = 16384;
  const long long numChunks = (numTets + chunk - 1) / chunk;
  std::vector<std::vector<int>> changed(static_cast<std::size_t>(numChunks));
  bool invalid = false;
  const double* keptA = kept.AbsorptionCoefficient.data();
  const double* keptS = kept.ReducedScatteringCoefficient.data();
  const double* keptEta = kept.RefractiveIndex.data();
#pragma omp parallel for schedule(static) reduction(|| : invalid)
  for (long long k = 0; k < numChunks; ++k)
  {
    std::vector<int>& mine = changed[static_cast<std::size_t>(k)];
    const long long end = std::min(numTets, (k + 1) * chunk);
    for (long long t = k * chunk; t < end; ++t)
    {
      // Bits, as FindChangedTets: a NaN that stays a NaN is no change.
      if (std::memcmp(keptA + 3 * t, absorption + 3 * t, 3 * sizeof(double)) == 0 &&
        std::memcmp(keptS + 3 * t, scattering + 3 * t, 3 * sizeof(double)) == 0 &&
        std::memcmp(keptEta + t, refractiveIndex + t, sizeof(double)) == 0)
      {
        continue;
      }
      mine.push_back(static_cast<int>(t));
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        const double a = absorption[3 * t + c], s = scattering[3 * t + c];
        invalid = invalid || !(std::isfinite(a) && a >= 0.0 && std::isfinite(s) && s >= 0.0 &&
          a + s > 0.0);
      }
      invalid = invalid || !(std::isfinite(refractiveIndex[t]) && refractiveIndex[t] > 0.0);
    }
  }
  if (invalid)
  {
    // Rare: Validate's message (its lowest invalid tet is a changed one, the
    // others were valid), from a copy; the kept material is not touched.
    OpticalProperties copy;
    copy.AbsorptionCoefficient.assign(absorption, absorption + 3 * numTets);
    copy.ReducedScatteringCoefficient.assign(scattering, scattering + 3 * numTets);
    copy.RefractiveIndex.assign(refractiveIndex, refractiveIndex + numTets);
    copy.Validate(static_cast<int>(numTets));
    throw Error("DiffusionFrontEnd::UpdateKeptMaterial: invalid material"); // not reached
  }
  std::size_t total = 0;
  for (const auto& c : changed)
    total += c.size();
  std::vector<int> all;
  all.reserve(total);
  for (const auto& c : changed)
    all.insert(all.end(), c.begin(), c.end());
  double* outA = kept.AbsorptionCoefficient.data();
  double* outS = kept.ReducedScatteringCoefficient.data();
  double* outEta = kept.RefractiveIndex.data();
  for (const int t : all)
  {
    const std::size_t k = static_cast<std::size_t>(t);
    std::copy(absorption + 3 * k, absorption + 3 * k + 3, outA + 3 * k);
    std::copy(scattering + 3 * k, scattering + 3 * k + 3, outS + 3 * k);
    outEta[k] = refractiveIndex[k];
  }
  PendingChanges_ = std::move(all);
  return true;
}

bool DiffusionFrontEnd::SolveKeptMaterial(std::shared_ptr<const TetMesh> mesh,
  std::vector<double> irradiance, const DiffusionProblem& light, const SolveRequest& request,
  SolveResult& result)
{
  if (!HasKeptMaterial(mesh))
  {
    throw Error("DiffusionFrontEnd::SolveKeptMaterial: no material kept from a solve on this mesh");
  }
  CheckDomain(request); // before the kept material is taken
  OpticalProperties material = std::move(LastMaterial_);
  LastMaterial_ = OpticalProperties();
  return SolveMaterial(
    std::move(mesh), std::move(material), std::move(irradiance), light, request, result, true);
}

bool DiffusionFrontEnd::Solve(std::shared_ptr<const TetMesh> mesh, OpticalProperties material,
  std::vector<double> irradiance, const DiffusionProblem& light, const SolveRequest& request,
  SolveResult& result)
{
  return SolveMaterial(
    std::move(mesh), std::move(material), std::move(irradiance), light, request, result, false);
}

bool DiffusionFrontEnd::SolveMaterial(std::shared_ptr<const TetMesh> mesh,
  OpticalProperties material, std::vector<double> irradiance, const DiffusionProblem& light,
  const SolveRequest& request, SolveResult& result, bool kept)
{
  CheckDomain(request);
  const DiffusionSolverTraits& traits = GetDiffusionSolverRegistry().Get(SolverName_).Properties;
  if (mesh != Mesh_)
  {
    Solver_->Reset(); // a new geometry: the previous solution is no start point
    Mesh_ = mesh;
    ForgetLast();
  }
  // The incremental assembly of a paint is the in-process vertex solvers'
  // (the distributed variant keeps its hierarchy across paints itself).
  const bool continuous = request.Domain == SolveDomain::ContinuousWave;
  // The material is kept for the next solve's SolveKeptMaterial (a relight)
  // by every continuous-wave vertex solve, the distributed one too (its
  // piece's material); only the in-process ones compare a new material with
  // it (the distributed solver compares a new one itself, and is told the
  // changes of the kept one below).
  const bool keeps = traits.UnknownsAtVertices && continuous;
  const bool incremental = keeps && !Comm_.IsMPI();
  ChangedTets_ = -1;
  if (incremental)
  {
    DetectChangedTets(material, irradiance, kept);
  }
  else if (keeps && kept)
  {
    // The kept material passed back to the distributed solver, which keeps
    // the same material: it differs in the tets UpdateKeptMaterial wrote (a
    // paint) or none (a relight), on this rank, so the solver neither
    // compares nor validates the rest (DistributedVertexSolver::SetChangedTets;
    // it counts the changes over the ranks and decides the update itself).
    std::vector<int> changed;
    if (PendingChanges_)
      changed = std::move(*PendingChanges_);
    Solver_->SetChangedTets(std::move(changed), true);
  }
  ForgetLast(); // until this solve succeeds

  DiffusionProblem problem = light;
  problem.Mesh = mesh.get();
  problem.Material = &material;
  problem.Irradiance = &irradiance;
  result = SolveResult();
  try
  {
    if (!SolveOnce(problem, request, result))
    {
      return false; // aborted by the progress callback
    }
    std::string unconverged = traits.IsStochastic ? "" : UnconvergedChannels(result.Report);
    if (!unconverged.empty())
    {
      // Never a non-converged result: a kept hierarchy (values-only set-up
      // after a paint, a relight) or a warm start may be what failed, so
      // solve again after a full set-up, cold.
      Solver_->Reset();
      ChangedTets_ = -1;
      result = SolveResult();
      if (!SolveOnce(problem, request, result))
      {
        return false;
      }
      result.Report.Resolved = true;
      unconverged = UnconvergedChannels(result.Report);
      if (!unconverged.empty() && !request.AcceptUnconverged)
      {
        // A NaN/inf field says more than "did not converge" (an overflow).
        RequireFinite(result.Fluence, "Fluence (" + SolverName_ + " solver)", OverflowCause());
        throw Error("the " + std::string(Comm_.IsMPI() ? "distributed " : "") + SolverName_ +
          " solve did not converge, also after a full set-up (" +
          unconverged + "; RelTol " + FormatNumber(Solver_->GetRelTol()) + ", MaxIter " +
          std::to_string(Solver_->GetMaxIter()) + ", linear solver " +
          result.Report.LinearSolver +
          "): no result. Raise MaxIter or RelTol, or choose another LinearSolver");
      }
    }
    // Never hand on a NaN/inf fluence as a result (e.g. a light power of
    // 1e300 overflows the right-hand side).
    RequireFinite(irradiance, "the boundary irradiance", OverflowCause());
    RequireFinite(result.Fluence, "Fluence (" + SolverName_ + " solver)", OverflowCause());
    ReadOut(problem, request, result);
  }
  catch (...)
  {
    Solver_->Reset();
    ForgetLast();
    throw;
  }
  if (keeps && IncrementalAssembly_)
  {
    LastMaterial_ = std::move(material);
    LastIrradiance_ = std::move(irradiance);
    HaveLast_ = true;
  }
  return true;
}

bool DiffusionFrontEnd::SolveOnce(
  const DiffusionProblem& problem, const SolveRequest& request, SolveResult& result)
{
  if (problem.Collimated == CollimatedModel::ExtendedMoments &&
    !GetDiffusionSolverRegistry().Get(SolverName_).Properties.IsStochastic)
  {
    // divergence and fem solve the extended-moments model with the Robin
    // rule of the Fresnel moments (quadgraph and grid refuse the model; the
    // photons solve the transport, no Robin rule).
    result.Rule = Fresnel::BoundaryRule::Moments;
  }
  switch (request.Domain)
  {
    case SolveDomain::Frequency:
      return SolveFrequency(problem, request, result);
    case SolveDomain::Time:
      Solver_->SetDetectors(request.Detectors);
      if (!Solver_->SolveTimeResolved(problem, request.Gates, request.Detectors,
            request.Snapshots, result.Time, result.Report))
      {
        return false;
      }
      result.Fluence = result.Time.IntegratedFluence;
      return true;
    case SolveDomain::ContinuousWave:
    default:
      Solver_->SetDetectors(request.Detectors);
      return Solver_->Solve(problem, result.Fluence, result.Report);
  }
}

bool DiffusionFrontEnd::SolveFrequency(
  const DiffusionProblem& problem, const SolveRequest& request, SolveResult& result)
{
  std::vector<std::complex<double>> complexFluence;
  if (!Solver_->SolveFrequencyDomain(problem, request.Frequency, complexFluence, result.Report))
  {
    return false;
  }
  // The extended collimated model: the total Phi = Phi_d + the modulated
  // beam; Fluence is |Phi_d| + |E_c| so that Fluence - CollimatedFluence is
  // the diffuse amplitude downstream (vtkOutgoingRadiance); Amplitude and
  // Phase are those of the total. The detectors read the diffuse Phi_d.
  const SolverReport& report = result.Report;
  const std::size_t n = complexFluence.size();
  const bool beam =
    report.CollimatedFluence.size() == n && report.CollimatedFluencePhase.size() == n;
  result.Amplitude.resize(n);
  result.Phase.resize(n);
  result.Fluence.resize(n);
  std::vector<double> real(n), imag(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    const std::complex<double> diffuse = beam
      ? complexFluence[i] - std::polar(report.CollimatedFluence[i], report.CollimatedFluencePhase[i])
      : complexFluence[i];
    real[i] = diffuse.real();
    imag[i] = diffuse.imag();
    result.Amplitude[i] = std::abs(complexFluence[i]);
    result.Phase[i] = std::arg(complexFluence[i]);
    result.Fluence[i] = beam ? std::abs(diffuse) + report.CollimatedFluence[i] : result.Amplitude[i];
  }
  if (!request.Detectors.empty())
  {
    // The readings are linear in (phi, q): read the real part with q
    // (modulated in phase with the sources) and the imaginary part without,
    // then take amplitude and phase.
    const auto re = ReadDetectors(*problem.Mesh, *problem.Material, request.Detectors, real,
      problem.Irradiance, result.Rule);
    const auto im = ReadDetectors(
      *problem.Mesh, *problem.Material, request.Detectors, imag, nullptr, result.Rule);
    result.Readings = re;
    result.FluencePhase.resize(re.size());
    result.ExitancePhase.resize(re.size());
    for (std::size_t k = 0; k < re.size(); ++k)
    {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        const std::complex<double> f(re[k].Fluence[c], im[k].Fluence[c]);
        const std::complex<double> j(re[k].Exitance[c], im[k].Exitance[c]);
        result.Readings[k].Fluence[c] = std::abs(f);
        result.Readings[k].Exitance[c] = std::abs(j);
        result.FluencePhase[k][c] = std::arg(f);
        result.ExitancePhase[k][c] = std::arg(j);
      }
    }
  }
  return true;
}

namespace
{
/// The detector readings of a time-resolved run: the time integrals of the
/// gate averages (the continuous-wave readings when the gates cover the
/// whole response).
std::vector<DetectorReading> IntegrateGates(const TimeResolvedResult& time)
{
  const double width = time.Gates.GetWidth();
  std::vector<DetectorReading> readings = time.Readings.front();
  for (std::size_t k = 0; k < readings.size(); ++k)
  {
    readings[k].Fluence.fill(0.0);
    readings[k].Exitance.fill(0.0);
    for (const auto& gate : time.Readings)
    {
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        readings[k].Fluence[c] += width * gate[k].Fluence[c];
        readings[k].Exitance[c] += width * gate[k].Exitance[c];
      }
    }
  }
  return readings;
}
}

void DiffusionFrontEnd::ReadOut(
  const DiffusionProblem& problem, const SolveRequest& request, SolveResult& result)
{
  TalliedReadouts tallied;
  const bool hasTallies = Solver_->GetTalliedReadouts(tallied);
  if (hasTallies)
  {
    result.HasTalliedBalance = true;
    result.TalliedInjected = tallied.Injected;
    result.TalliedAbsorbed = tallied.Absorbed;
    result.TalliedEscaped = tallied.Escaped;
  }
  const bool detectors = !request.Detectors.empty();
  if (request.Domain == SolveDomain::Time)
  {
    if (hasTallies)
    {
      result.GateErrors = std::move(tallied.GateErrors);
    }
    if (detectors && !result.Time.Readings.empty())
    {
      result.Readings = IntegrateGates(result.Time);
    }
  }
  else if (request.Domain == SolveDomain::ContinuousWave && detectors)
  {
    if (hasTallies)
    {
      result.Readings = std::move(tallied.Readings);
      result.ReadingErrors = std::move(tallied.ReadingErrors);
    }
    else
    {
      // The detectors read the diffuse fluence (the unscattered beam of the
      // extended model does not leave as diffuse exitance).
      std::vector<double> diffuse = result.Fluence;
      for (std::size_t k = 0; k < result.Report.CollimatedFluence.size(); ++k)
      {
        diffuse[k] -= result.Report.CollimatedFluence[k];
      }
      result.Readings = ReadDetectors(*problem.Mesh, *problem.Material, request.Detectors,
        diffuse, problem.Irradiance, result.Rule);
    }
  }
  if (request.Domain != SolveDomain::Frequency)
  {
    result.FluencePhase.assign(result.Readings.size(), { 0.0, 0.0, 0.0 });
    result.ExitancePhase.assign(result.Readings.size(), { 0.0, 0.0, 0.0 });
  }
}

void DiffusionFrontEnd::ComputePowerBalance(const TetMesh& mesh, const OpticalProperties& material,
  const std::vector<double>& resultFluence, const std::vector<double>& irradiance,
  const Sources* sources, const SolveResult& result,
  SolveDomain domain, std::array<double, NumberOfChannels>& injected,
  std::array<double, NumberOfChannels>& absorbed, std::array<double, NumberOfChannels>& escaped)
{
  if (domain == SolveDomain::Frequency)
  {
    throw Error("no power balance in the frequency domain: the fluence is complex");
  }
  if (result.HasTalliedBalance)
  {
    injected = result.TalliedInjected;
    absorbed = result.TalliedAbsorbed;
    escaped = result.TalliedEscaped;
    return;
  }
  // The extended collimated model: Fluence = phi_d + E_c. The diffuse
  // field's balance is read from phi_d with the solve's Robin rule; the beam
  // adds what entered (injected), what it deposited directly (absorbed) and
  // what leaves unscattered, entering - scattered - absorbed (escaped;
  // DiffuseOptics.md, "Power balance").
  const SolverReport& report = result.Report;
  std::vector<double> fluence = resultFluence;
  const bool beam = report.CollimatedFluence.size() == fluence.size();
  if (beam)
  {
    for (std::size_t k = 0; k < fluence.size(); ++k)
    {
      fluence[k] -= report.CollimatedFluence[k];
    }
  }
  const PowerBalance balance =
    translucency::ComputePowerBalance(mesh, material, fluence, &irradiance, result.Rule);
  std::array<double, NumberOfChannels> sourcePower{};
  if (sources)
  {
    sourcePower = sources->InjectedPower(mesh, material);
  }
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    injected[c] = balance.BoundaryInjected[c] + sourcePower[c];
    absorbed[c] = balance.Absorbed[c];
    escaped[c] = balance.Escaped[c];
    if (beam)
    {
      injected[c] += report.CollimatedEntering[c];
      absorbed[c] += report.CollimatedAbsorbed[c];
      escaped[c] +=
        report.CollimatedEntering[c] - report.CollimatedScattered[c] - report.CollimatedAbsorbed[c];
    }
  }
}

} // namespace translucency
