/**
 * @file   vtkTranslucencyParallel.h
 * @brief  Runs a filter's serial RequestData on data distributed over MPI ranks.
 *
 * Under `mpiexec -n N pvbatch` (or an MPI pvserver) every rank executes the
 * pipeline on its own piece of the data. Our solvers need the whole object
 * (a partition face is not a lit outer surface, a shared vertex is one
 * unknown), so, while the global controller has more than one process, each
 * filter calls RunGathered() first thing in RequestData:
 *
 *  1. every rank sends its input pieces (every input port) to rank 0, which
 *     merges them into one data set: ghost cells (vtkGhostType) are dropped,
 *     points shared by pieces become one point, matched by the point
 *     `GlobalIds` when every piece has them, else by exactly equal
 *     coordinates; image pieces are put together by extent, composite data
 *     leaf by leaf;
 *  2. rank 0 runs the filter's own serial RequestData on the merged data;
 *  3. rank 0 broadcasts the outcome: on failure every rank reports the same
 *     error and returns empty outputs; on success the outputs go back:
 *     - GatherMode::SameMesh (the first output is the input mesh with new or
 *       changed arrays): each rank's output is its own input piece, partition
 *       and ghost cells kept, with the arrays of the serial result, point by
 *       point and cell by cell, so shared points get the same value on every
 *       rank;
 *     - GatherMode::RankZero (a new mesh, e.g. TetGen's tets or a cut): rank 0
 *       holds the whole result, the other ranks an empty output of the same
 *       type (Redistribute DataSet spreads it again).
 *     Outputs after the first are always RankZero.
 *
 * Every rank takes part in every collective on every path (empty pieces,
 * errors), so no rank waits for another that returned early. With one
 * process (no MPI, or a single rank) RunGathered returns false at once and
 * the filter runs as before, at no cost.
 */
#ifndef vtkTranslucencyParallel_h
#define vtkTranslucencyParallel_h

#include <functional>

class vtkAlgorithm;
class vtkInformation;
class vtkInformationVector;

namespace vtkTranslucencyParallel
{
/// What the ranks' outputs are after the serial run on rank 0 (see the file comment).
enum class GatherMode
{
  SameMesh, ///< first output = the input mesh with arrays: scattered back per rank
  RankZero  ///< the whole result on rank 0, empty outputs elsewhere
};

/// The filter's own RequestData, called on rank 0 with the merged inputs.
using SerialRequest =
  std::function<int(vtkInformation*, vtkInformationVector**, vtkInformationVector*)>;

/**
 * Run `serial` on the data of every rank gathered to rank 0 and hand the
 * outputs back (see the file comment). Returns false when there is nothing to
 * distribute (one process, or called while a gathered run is under way on
 * this thread, i.e. from `serial` itself or a filter it runs): the caller
 * then runs its serial code. Returns true when it ran the filter; `result` is
 * then what RequestData must return (1 on success, 0 on every rank on failure).
 */
bool RunGathered(vtkAlgorithm* self, vtkInformation* request, vtkInformationVector** inputVector,
  vtkInformationVector* outputVector, GatherMode mode, const SerialRequest& serial, int& result);

/**
 * True while a gathered run is under way on this thread (rank 0 runs a
 * filter's serial code on the merged data, alone): a filter that would run
 * per piece with collectives must then run serially instead.
 */
bool IsGathering();
}

#endif
