#include "DiffusionSolver.h"

#include <complex>
#include <utility>

namespace translucency
{

// The defaults refuse, naming the solver: a caller holding any
// DiffusionSolver asks for a domain and gets either the solve or this error
// (the registry traits SupportsFrequency / SupportsTime say which, without
// creating a solver).
bool DiffusionSolver::SolveFrequencyDomain(const DiffusionProblem& /*problem*/,
  double frequency, std::vector<std::complex<double>>& /*fluence*/, SolverReport& /*report*/)
{
  throw Error("the " + GetName() + " solver has no frequency domain (modulation frequency " +
    std::to_string(frequency) + " Hz)");
}

bool DiffusionSolver::SolveTimeResolved(const DiffusionProblem& /*problem*/,
  const TimeGates& /*gates*/, const std::vector<Detector>& /*detectors*/,
  const std::vector<int>& /*snapshotGates*/, TimeResolvedResult& /*result*/,
  SolverReport& /*report*/)
{
  throw Error("the " + GetName() + " solver has no time gates");
}

void AddCollimatedFluence(CollimatedSource& collimated, std::vector<double>& fluence,
  SolverReport& report)
{
  // The total fluence rate: diffuse plus the unscattered beam.
  for (std::size_t k = 0; k < fluence.size(); ++k)
  {
    fluence[k] += collimated.Fluence[k];
  }
  report.CollimatedFluence = std::move(collimated.Fluence);
  report.CollimatedEntering = collimated.Entering;
  report.CollimatedScattered = collimated.Scattered;
  report.CollimatedAbsorbed = collimated.Absorbed;
}

void AddCollimatedFluence(const CollimatedSource& collimated,
  const std::vector<std::complex<double>>& modulated,
  std::vector<std::complex<double>>& fluence, SolverReport& report)
{
  // The total: diffuse plus the modulated unscattered beam; the report keeps
  // the beam's amplitude and phase (the detectors read the diffuse part) and
  // its continuous-wave powers.
  report.CollimatedFluence.resize(fluence.size());
  report.CollimatedFluencePhase.resize(fluence.size());
  for (std::size_t k = 0; k < fluence.size(); ++k)
  {
    fluence[k] += modulated[k];
    report.CollimatedFluence[k] = std::abs(modulated[k]);
    report.CollimatedFluencePhase[k] = std::arg(modulated[k]);
  }
  report.CollimatedEntering = collimated.Entering;
  report.CollimatedScattered = collimated.Scattered;
  report.CollimatedAbsorbed = collimated.Absorbed;
}

} // namespace translucency
