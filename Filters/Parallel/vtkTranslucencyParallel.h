/**
 * @file   vtkTranslucencyParallel.h
 * @brief  The gathered path of the dispatcher (vtkTranslucencyDispatch.h):
 *         a filter's serial RequestData on data distributed over MPI ranks.
 *         Private to the filters.
 *
 * Our solvers need the whole object for the stages that cannot run per
 * piece (a partition face is not a lit outer surface, a shared vertex is one
 * unknown), so, for a plan of kind Gathered:
 *
 *  1. every rank sends its input pieces (every input port) to rank 0, which
 *     merges them into one data set: ghost cells (vtkGhostType) are dropped,
 *     points shared by pieces become one point, matched by the point
 *     `GlobalIds` when every piece has them, else by exactly equal
 *     coordinates; image pieces are put together by extent, composite data
 *     leaf by leaf;
 *  2. rank 0 runs the filter's own serial path on the merged data, inside a
 *     vtkTranslucencyCommunicator::LocalScope (any filter run there is
 *     serial: nothing waits for the other ranks);
 *  3. rank 0 broadcasts the outcome: on failure every rank reports the same
 *     error and returns empty outputs; on success the outputs go back:
 *     - GatherMode::SameMesh (the first output is the input mesh with new or
 *       changed arrays): each rank's output is its own input piece, partition
 *       and ghost cells kept, with the arrays of the serial result, point by
 *       point and cell by cell, so shared points get the same value on every
 *       rank; the field arrays of the serial result, except those it passed
 *       through from its input unchanged, which stay each piece's own (they
 *       may number the piece's cells, as Paint's PaintedCellIds);
 *     - GatherMode::RankZero (a new mesh, e.g. TetGen's tets or a cut): rank 0
 *       holds the whole result, the other ranks an empty output of the same
 *       type (Redistribute DataSet spreads it again).
 *     Outputs after the first are always RankZero.
 *
 * Replicated (`replicate`, vtkTranslucencyParallelPlan::Replicated): step 1
 * gathers the pieces to every rank (AllGather), each merges them alike, and
 * step 2 runs on every rank,
 * inside a LocalScope and a vtkTranslucencyCommunicator::ReplicatedScope of
 * `comm` (the serial path may share its work over the ranks: Solve
 * Diffusion's Monte Carlo traces a share of the photons on each); a failure
 * on any rank is every rank's (the lowest failing rank's message); step 3
 * hands rank 0's outputs back as above. Every rank then holds the whole
 * data for the run.
 *
 * Every rank takes part in every collective (empty pieces, errors), so no
 * rank waits for another that returned early.
 */
#ifndef vtkTranslucencyParallel_h
#define vtkTranslucencyParallel_h

#include <functional>

class vtkAlgorithm;
class vtkInformation;
class vtkInformationVector;
class vtkTranslucencyCommunicator;

namespace vtkTranslucencyParallel
{
/// What the ranks' outputs are after the serial run on rank 0 (see the file comment).
enum class GatherMode
{
  SameMesh, ///< first output = the input mesh with arrays: scattered back per rank
  RankZero  ///< the whole result on rank 0, empty outputs elsewhere
};

/// The filter's serial RequestData, called on rank 0 with the merged inputs.
using SerialRequest =
  std::function<int(vtkInformation*, vtkInformationVector**, vtkInformationVector*)>;

/**
 * Collective over `comm` (more than one process). Run `serial` on the data
 * of every rank gathered to rank 0 (to every rank if `replicate`) and hand
 * the outputs back (see the file comment). Returns what RequestData must
 * return (1 on success, 0 on every rank on failure).
 */
int RunGathered(vtkAlgorithm* self, vtkInformation* request, vtkInformationVector** inputVector,
  vtkInformationVector* outputVector, GatherMode mode, const SerialRequest& serial,
  const vtkTranslucencyCommunicator& comm, bool replicate = false);
}

#endif
