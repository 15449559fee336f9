/**
 * @file DistributedSources.h
 * @brief Interior sources (point sources, pencil beams) and detectors of the
 * distributed vertex solve (DistributedVertexSolver): each rank holds its
 * owned tets and knows which of their boundary faces are physical (no tet of
 * any rank shares them); no rank sees the whole mesh.
 *
 *  - A point source is placed by every rank in its own tets (TetLocator);
 *    the lowest rank that finds it adds its load (P lambda_a(x) at the tet's
 *    4 vertices, as Sources::ComputeLoad); a source found on no rank is the
 *    same error on every rank, with the global tet count and bounds.
 *  - A pencil beam's entry (Farrell et al. 1992, as Sources::Place) is the
 *    closest point of the physical surface: each rank's closest physical
 *    face, the global minimum by (distance, rank) (MPI_MINLOC: a tie goes to
 *    the lowest rank); the winner sends the point, the face's normal and the
 *    material of the tet under it, and every rank derives the same refracted
 *    direction, Fresnel transmittance and equivalent point sources, placed as
 *    above. The surface tolerance (half the mean physical boundary edge) is
 *    reduced over the ranks. Nothing walks the mesh: the model needs only the
 *    entry face and its tet.
 *  - A detector's surface point is found the same way; a point detector is
 *    read by the winner, a fibre's disc samples by every rank on its own
 *    physical faces (the same sub-triangles as LocateDetectors), their
 *    area-weighted sums and areas summed over the ranks (MPI_Allreduce): the
 *    readings are the same on every rank.
 *
 * Every function is collective over `comm` (ranks with empty pieces too)
 * and throws translucency::Error with the same message on every rank.
 */
#pragma once

#include "Detectors.h"
#include "InteriorSources.h"
#include "OpticalProperties.h"
#include "TetMesh.h"

#include <mpi.h>

#include <vector>

namespace translucency
{

/// One rank's view of the distributed mesh.
struct DistributedPiece
{
  const TetMesh* Mesh = nullptr;          ///< owned tets on the local points (unused if no tets)
  bool HasTets = false;                   ///< false for an empty piece
  int NumberOfPoints = 0;                 ///< local points (the size of point arrays / 3)
  const std::vector<char>* Physical = nullptr; ///< per boundary triangle of Mesh: physical boundary
  const OpticalProperties* Material = nullptr; ///< per owned tet
};

/**
 * The consistent load of the sources (W per channel) at the local points:
 * 3 values per local point, non-zero only on the rank that owns each
 * source's tet; summed over the ranks it is the serial ComputeLoad.
 */
std::vector<double> ComputeDistributedSourceLoad(
  MPI_Comm comm, const DistributedPiece& piece, const Sources& sources);

/**
 * The detector readings of a solution (`fluence`, `irradiance`: 3 values per
 * local point, shared points with the same value on every rank), the same
 * on every rank; the serial ReadDetectors up to round-off.
 */
std::vector<DetectorReading> ReadDistributedDetectors(MPI_Comm comm, const DistributedPiece& piece,
  const std::vector<Detector>& detectors, const std::vector<double>& fluence,
  const std::vector<double>* irradiance,
  Fresnel::BoundaryRule rule = Fresnel::BoundaryRule::Fit);

} // namespace translucency
