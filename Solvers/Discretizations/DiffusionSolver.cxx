#include "DiffusionSolver.h"

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

} // namespace translucency
