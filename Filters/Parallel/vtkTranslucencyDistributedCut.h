/**
 * @file   vtkTranslucencyDistributedCut.h
 * @brief  vtkStrokeCut per piece under MPI with the relaxation on or a
 *         stroke: the stroke shared by every rank, and the cut front (the
 *         kept tets with a vertex on the removed side) all-gathered so every
 *         rank relaxes it exactly as the serial cut (translucency::CutFront).
 *         Private to the filters; Documentation/Parallel.md, "Stroke Cut per piece".
 *
 * Both functions are collective over the global vtkMultiProcessController:
 * every rank calls them, a rank with an empty piece too.
 */
#ifndef vtkTranslucencyDistributedCut_h
#define vtkTranslucencyDistributedCut_h

#include "TetCut.h"

#include <string>
#include <vector>

class vtkUnstructuredGrid;

namespace translucency
{
class TetMesh;
}

namespace vtkTranslucencyDistributedCut
{
/**
 * The stroke (3 coordinates per point, mm) of the lowest rank whose `local`
 * stroke is not empty, in `shared` on every rank (empty if no rank has one).
 * Returns false on every rank if another rank's non-empty stroke differs from
 * it (a stroke split over the ranks: the caller gathers instead).
 */
bool ShareStroke(const std::vector<double>& local, std::vector<double>& shared);

/// Sizes of the last front exchange (the same on every rank).
struct FrontStatistics
{
  long long Points = 0; ///< front points, each once
  long long Tets = 0;   ///< front tets, each once
  long long Bytes = 0;  ///< bytes every rank received in the all-gather
};

/**
 * Relax the cut over all ranks. `piece` is the rank's input (its point
 * GlobalIds and ghost marks; empty or null on a rank without cells), `mesh`
 * its tets (null without cells), `side` F at its points, `local` its cut
 * without relaxation (kept tets and points). `relax` carries the settings
 * (factor, iterations, dihedral bound) and gets the statistics of the whole
 * relaxation. Points are matched by GlobalIds when every rank with points has
 * them, else by exact coordinates. `positions` (3 per kept point of `local`)
 * get the relaxed coordinates. Returns false with the same `error` on every rank.
 */
bool RelaxFront(vtkUnstructuredGrid* piece, const translucency::TetMesh* mesh,
  const std::vector<double>& side, const translucency::TetCut& local, translucency::TetCut& relax,
  const translucency::TetCut::SideFunction& F, std::vector<double>& positions,
  FrontStatistics& statistics, std::string& error);
}

#endif
