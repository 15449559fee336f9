/**
 * @file   vtkTranslucencyDistributedPieces.h
 * @brief  Collectives for filters that run on each MPI rank's own piece
 *         without gathering (vtkAssignScatteringCoefficients' per-tet modes):
 *         one decision and one error message on every rank.
 *
 * They use the global vtkMultiProcessController (any controller; with one
 * process IsAvailable() is false and nothing here is called). Every function
 * but IsAvailable() is collective: every rank calls it, a rank with an empty
 * piece too.
 */
#ifndef vtkTranslucencyDistributedPieces_h
#define vtkTranslucencyDistributedPieces_h

#include <string>

class vtkUnstructuredGrid;

namespace vtkTranslucencyDistributedPieces
{
/// True if the global controller runs more than one process.
bool IsAvailable();
/// The rank of this process (0 without a controller).
int GetRank();
/// Sum over the ranks.
long long Sum(long long value);
/// Sum over the ranks below this one (0 on rank 0).
long long ExclusiveSum(long long value);
/// True on every rank if `value` is true on some rank.
bool Any(bool value);
/// "" on every rank if every `localError` is empty, else the lowest such
/// rank's message, prefixed "rank r: ", on every rank.
std::string AgreeOnError(const std::string& localError);
/// True if `piece` has a cell flagged vtkGhostType DUPLICATECELL (not collective).
bool HasGhostCells(vtkUnstructuredGrid* piece);
}

#endif
