#include "ReplicatedMonteCarlo.h"

#include "DiffusionSolverFactory.h"
#include "Error.h"

#include <climits>
#include <string>

namespace translucency
{

namespace
{
/// The registry's distributed variant of "montecarlo" (trait Replicated),
/// registered when this layer is loaded.
const bool Registered = [] {
  RegisterDistributedDiffusionSolver(
    "montecarlo",
    [] { return std::unique_ptr<DiffusionSolver>(std::make_unique<ReplicatedMonteCarloSolver>()); },
    true);
  return true;
}();
} // namespace

ReplicatedMonteCarloSolver::ReplicatedMonteCarloSolver()
{
  SetCommunicator(Communicator());
}

void ReplicatedMonteCarloSolver::SetCommunicator(const Communicator& comm)
{
  Comm_ = GetMPIComm(comm);
  int rank = 0, size = 1;
  MPI_Comm_rank(Comm_, &rank);
  MPI_Comm_size(Comm_, &size);
  SetShare(rank, size);
}

void ReplicatedMonteCarloSolver::SumOverShare(double* values, std::size_t count) const
{
  // In slices an int can count (a tally of more than 2^31 entries).
  for (std::size_t first = 0; first < count; first += INT_MAX)
  {
    const int n = static_cast<int>(std::min<std::size_t>(INT_MAX, count - first));
    const int status =
      MPI_Allreduce(MPI_IN_PLACE, values + first, n, MPI_DOUBLE, MPI_SUM, Comm_);
    if (status != MPI_SUCCESS)
    {
      throw Error("the Monte Carlo's sum over the ranks failed (MPI error " +
        std::to_string(status) + ")");
    }
  }
}

} // namespace translucency
