// MonteCarloSolver's answers to the DiffusionSolver interface beside
// Solve(): the time domain (its time-of-flight tallies) and the tallied
// read-outs the front end hands on (DiffusionFrontEnd::Solve).
#include "MonteCarlo.h"

namespace translucency
{

bool MonteCarloSolver::SolveTimeResolved(const DiffusionProblem& problem,
  const TimeGates& gates, const std::vector<Detector>& detectors,
  const std::vector<int>& snapshotGates, TimeResolvedResult& result, SolverReport& report)
{
  if (!snapshotGates.empty())
  {
    throw Error("the montecarlo solver tallies the time gates at the detectors only: no fluence "
                "snapshots per gate (use the divergence or fem solver)");
  }
  const TimeGates previousGates = Gates_;
  const std::vector<Detector> previousDetectors = Detectors_;
  Gates_ = gates;
  Detectors_ = detectors;
  std::vector<double> fluence;
  bool solved = false;
  try
  {
    solved = Solve(problem, fluence, report);
  }
  catch (...)
  {
    Gates_ = previousGates;
    Detectors_ = previousDetectors;
    throw;
  }
  Gates_ = previousGates;
  Detectors_ = previousDetectors;
  if (!solved)
  {
    return false;
  }
  result = TimeResolvedResult();
  result.Gates = gates;
  result.Readings = GateReadings_;
  result.IntegratedFluence = std::move(fluence); // all time: the photons' CW fluence
  return true;
}

bool MonteCarloSolver::GetTalliedReadouts(TalliedReadouts& readouts) const
{
  readouts.Readings = Readings_;
  readouts.ReadingErrors = ReadingErrors_;
  readouts.GateReadings = GateReadings_;
  readouts.GateErrors = GateReadingErrors_;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    readouts.Injected[c] = Balance_[c].Injected;
    readouts.Absorbed[c] = Balance_[c].Absorbed;
    readouts.Escaped[c] = Balance_[c].Escaped;
  }
  return true;
}

} // namespace translucency
