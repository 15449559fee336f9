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
 *  - the path: Serial (size one), PerPiece, Distributed, Gathered
 *    (vtkTranslucencyParallel::RunGathered: merge on rank 0, the serial path
 *    there inside a LocalScope, the outputs back) or Replicated (the pieces
 *    gathered to and merged on every rank, the serial path on every rank inside a LocalScope and a
 *    ReplicatedScope, rank 0's outputs back);
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
#include <utility>

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

/// Make every output of `outputVector` a clean empty data set
/// (vtkTranslucencyOutputGuard::MakeEmpty). Called by RequestUpdateExtent:
/// see UpdateExtent().
void EmptyOutputs(vtkInformationVector* outputVector);
}

/**
 * What the filter templates below need of a filter's protected members:
 * PlanParallel, RequestSerial, ParallelPath, ParallelPlan and the
 * superclass's RequestUpdateExtent. Every public filter names it a friend
 * (`friend struct vtkTranslucencyDispatchAccess;`).
 */
struct vtkTranslucencyDispatchAccess
{
  template <class Filter>
  static int Run(Filter* self, vtkInformation* request, vtkInformationVector** inputVector,
    vtkInformationVector* outputVector, vtkTranslucencyDispatch::PiecePath perPiece,
    vtkTranslucencyDispatch::PiecePath distributed)
  {
    return vtkTranslucencyDispatch::Run(
      self, request, inputVector, outputVector,
      [self](vtkInformationVector** i, const vtkTranslucencyCommunicator& c)
      { return self->PlanParallel(i, c); },
      { [self](vtkInformation* r, vtkInformationVector** i, vtkInformationVector* o)
        { return self->RequestSerial(r, i, o); },
        std::move(perPiece), std::move(distributed) },
      { self->ParallelPath, self->ParallelPlan });
  }

  template <class Filter>
  static int UpdateExtent(Filter* self, vtkInformation* request,
    vtkInformationVector** inputVector, vtkInformationVector* outputVector)
  {
    vtkTranslucencyDispatch::EmptyOutputs(outputVector);
    return self->Filter::Superclass::RequestUpdateExtent(request, inputVector, outputVector);
  }
};

namespace vtkTranslucencyDispatch
{
/**
 * A filter's whole RequestData: Run() with the filter's PlanParallel as the
 * planner, its RequestSerial as the serial path, the given per-piece and
 * distributed paths (null: the filter has none) and its ParallelPath and
 * ParallelPlan as the record.
 * @code
 * int vtkMyFilter::RequestData(vtkInformation* request,
 *   vtkInformationVector** inputVector, vtkInformationVector* outputVector)
 * {
 *   return vtkTranslucencyDispatch::RunFilter(this, request, inputVector, outputVector);
 * }
 * @endcode
 */
template <class Filter>
int RunFilter(Filter* self, vtkInformation* request, vtkInformationVector** inputVector,
  vtkInformationVector* outputVector, PiecePath perPiece = nullptr,
  PiecePath distributed = nullptr)
{
  return vtkTranslucencyDispatchAccess::Run(
    self, request, inputVector, outputVector, std::move(perPiece), std::move(distributed));
}

/**
 * A filter's whole RequestUpdateExtent: empty the outputs, then the
 * superclass's. The pipeline calls RequestUpdateExtent only on a filter that
 * is about to execute, before anything upstream of it executes; when an
 * upstream filter then fails, VTK does not call this filter's RequestData at
 * all, so without this its output would keep the previous run's fields (a
 * stale Fluence after a typo in the material name). With it, the output of
 * every filter downstream of a failure is empty, as the failed filter's own
 * (vtkTranslucencyOutputGuard), until a run succeeds.
 */
template <class Filter>
int UpdateExtent(Filter* self, vtkInformation* request, vtkInformationVector** inputVector,
  vtkInformationVector* outputVector)
{
  return vtkTranslucencyDispatchAccess::UpdateExtent(self, request, inputVector, outputVector);
}
}

#endif
