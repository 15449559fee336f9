/**
 * @file   vtkTranslucencyDispatch.h
 * @brief  The one dispatcher of the filters' parallel seam: every public
 *         filter's RequestData is one call to Run() with its plan and its
 *         paths. Private to the filters.
 *
 * Run() owns, for every filter:
 *  - the communicator (vtkTranslucencyCommunicator::World(): ParaView's
 *    global controller, size one in a single process or inside another
 *    filter's gathered run: the one re-entrancy mechanism);
 *  - the plan: the filter's planner runs on every rank (collective: it may
 *    reduce a decision over the ranks), the override is applied
 *    (TRANSLUCENCY_PARALLEL=gathered, or the filter's deprecated variable),
 *    and the ranks check that they agree;
 *  - the agreed error: a bad override, a plan that differs between ranks, or
 *    a path that fails on some ranks only ends with the same message on every
 *    rank and empty outputs (vtkTranslucencyCommunicator::RunAgreed), before
 *    any rank goes on to a collective the others would not reach;
 *  - the path: Serial (size one), PerPiece, Distributed, or Gathered
 *    (vtkTranslucencyParallel::RunGathered: merge on rank 0, the serial path
 *    there inside a LocalScope, the outputs back);
 *  - ParallelPath: the filter's GetParallelPath() (what ran) and
 *    GetParallelPlan() (what it declares for more than one process, with the
 *    reason; also in a one-process run, so the plan can be tested serially).
 *
 * Ghost cells (vtkTranslucencyGhosts.h) and point keys
 * (vtkTranslucencyPieceFaces.h) are the paths' shared helpers.
 */
#ifndef vtkTranslucencyDispatch_h
#define vtkTranslucencyDispatch_h

#include "vtkTranslucencyCommunicator.h"
#include "vtkTranslucencyParallelPlan.h"

#include <functional>
#include <string>

class vtkAlgorithm;
class vtkInformation;
class vtkInformationVector;

namespace vtkTranslucencyDispatch
{
/// The filter's serial RequestData body (also the gathered run on rank 0).
using SerialPath =
  std::function<int(vtkInformation*, vtkInformationVector**, vtkInformationVector*)>;
/// A per-piece or distributed body: collective over `comm`.
using PiecePath = std::function<int(
  vtkInformationVector**, vtkInformationVector*, const vtkTranslucencyCommunicator& comm)>;
/// The filter's plan for more than one process; collective over `comm`
/// (size one in a single process: it must then decide alike without
/// communicating). Must not fail: a bad input is the path's error.
using Planner = std::function<vtkTranslucencyParallelPlan(
  vtkInformationVector**, const vtkTranslucencyCommunicator& comm)>;

struct Paths
{
  SerialPath Serial;       ///< required
  PiecePath PerPiece;      ///< for plans of kind PerPiece
  PiecePath Distributed;   ///< for plans of kind Distributed
};

/// Where the filter keeps what Run() reports (its GetParallelPath/Plan).
struct Record
{
  std::string& Path; ///< "serial", "per piece", "distributed" or "gathered"
  std::string& Plan; ///< the declared plan and reason (vtkTranslucencyParallelPlan::Describe)
};

/// RequestData of a filter: plan, agree, run the path (see the file comment).
int Run(vtkAlgorithm* self, vtkInformation* request, vtkInformationVector** inputVector,
  vtkInformationVector* outputVector, const Planner& planner, const Paths& paths, Record record);
}

#endif
