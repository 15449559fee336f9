/**
 * @file DistributedCollimatedSource.h
 * @brief The extended collimated source (CollimatedSource.h) of a tet mesh
 * distributed over MPI ranks, without gathering the mesh (issue 32;
 * Documentation/Parallel.md, "The extended collimated models").
 *
 * The beam of a directional light is a volume source: at a mesh point it is
 * E_c = E cos(theta_i) F_t(theta_i) / cos(theta_t) exp(-mu_t' s), from the
 * entry point where the ray from the point towards the light leaves the
 * object, with eta and mu_t' of the tet under the entry triangle. That entry
 * point may lie on any rank's part of the surface, so every rank all-gathers
 * the physical boundary surface with eta and mu_t' of each triangle's tet
 * (GatherBoundarySurface, O(N^(2/3)) of N tets, as the distributed Surface
 * Irradiance does) and casts the rays of its own points against it
 * (ComputeCollimatedBeamAtPoints: the serial arithmetic). The load, the
 * integral of mu_s' E_c phi_i over each tet, needs the tet's four vertex
 * values only: each rank integrates its own tets (AddCollimatedLoads), and
 * the loads at a point shared by ranks are summed at its owner with the rest
 * of the right-hand side. The beam's power (entering, scattered, absorbed)
 * is summed over the ranks. The result is the serial ComputeCollimatedSource
 * of the whole mesh at this rank's points, up to the order of the sums.
 *
 * Every call is collective over the communicator (a rank with an empty
 * piece too); an error is thrown on every rank with the same message.
 */
#pragma once

#include "CollimatedSource.h"
#include "DistributedNumbering.h"
#include "SurfaceLightKernel.h"

#include <mpi.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace translucency
{

class TetMesh;

/**
 * Collective: the lights, the uniform light's irradiance, the shadow flag,
 * the collimated model and `flag` (a caller's value) of the lowest rank with
 * `have` set (rank 0 if none) on every rank. A rank's empty piece may carry
 * no field data (no lights), while a solve's lights must be the same on
 * every rank.
 */
void AgreeOnLights(MPI_Comm comm, bool have, std::vector<LightSource>& lights,
  double& uniformIrradiance, bool& shadows, CollimatedModel& model, int& flag);

/**
 * The extended source of the directional lights on this rank's piece, kept
 * across calls as the serial CollimatedSourceCache keeps it (issue 32: a
 * paint must not cost a whole beam):
 *  - the gathered surface's geometry, while every rank's piece (geometry
 *    revision, keys) is the same; a paint that changes the material under the
 *    surface gathers the values of the physical triangles again (eta, mu_t',
 *    O(surface), no numbering);
 *  - the entry triangle of each beam at each local point (the rays), while
 *    the surface, the beams' directions and the shadow flag are the same;
 *  - E_c, evaluated again from the kept rays only when the material under
 *    the surface or a beam's power changed;
 *  - the loads (CollimatedLoadCache on this rank's tets: the tets whose
 *    material or vertex E_c changed, and the ring around them, integrated
 *    again; Load equal to a fresh computation bit for bit);
 *  - the entering power, while the surface's eta and the beams are the same.
 * GetLastUpdate() says what the last Compute did, the same on every rank.
 */
class DistributedCollimatedSource
{
public:
  /**
   * Collective. `mesh`: this rank's owned tets on its local points (null or
   * without tets: an empty piece); `keys`: one per local point; `used`: 1 per
   * local point of an owned tet; `material`: per owned tet; `lights`: the
   * same on every rank (the directional ones make beams, the others are
   * ignored). `out` gets Fluence, Beams and Load at the local points (3 per
   * point; Load is this rank's tets' share), and Entering, Scattered and
   * Absorbed of the whole mesh (the same on every rank).
   */
  void Compute(MPI_Comm comm, const TetMesh* mesh, const std::vector<PointKey>& keys,
    const std::vector<char>& used, const OpticalProperties& material,
    const std::vector<LightSource>& lights, bool shadows, CollimatedSource& out);
  /// Forget everything kept.
  void Clear();
  /// Whether the last Compute gathered the surface (false: kept, or no beam).
  bool GetSurfaceGathered() const { return Gathered_; }
  /// Whether the last Compute gathered the surface triangles' values only
  /// (a paint under the surface; the surface's geometry kept).
  bool GetSurfaceValuesGathered() const { return ValuesGathered_; }
  /// Physical boundary triangles of the kept surface (the same on every rank).
  long long GetSurfaceTriangles() const { return static_cast<long long>(Surface_.GetNumberOfTriangles()); }
  ///@{
  /// What the last Compute did, the same on every rank (as
  /// CollimatedSourceCache::GetLastUpdate()): "full" (rays cast, every tet
  /// integrated; also without beams), "loads" (the kept rays, the tets in
  /// GetTetsIntegrated() integrated again on some rank) or "kept" (nothing
  /// changed on any rank); and the tets integrated, summed over the ranks.
  const char* GetLastUpdate() const { return LastUpdate_; }
  long long GetTetsIntegrated() const { return TetsIntegrated_; }
  ///@}
  /// Bytes this rank keeps (surface, rays, E_c, loads).
  std::size_t GetMemoryBytes() const;
  /// Wall times of the last Compute on this rank (ms): the gather, the rays of
  /// this rank's points, the loads and the entering power.
  double GetGatherMilliseconds() const { return GatherMs_; }
  double GetRayMilliseconds() const { return RayMs_; }
  double GetLoadMilliseconds() const { return LoadMs_; }
  double GetEnteringMilliseconds() const { return EnteringMs_; }

private:
  /// Collective: whether the kept surface's geometry is of this call's pieces.
  bool GeometryKept(MPI_Comm comm, const TetMesh* mesh, const std::vector<PointKey>& keys) const;
  void Gather(MPI_Comm comm, const TetMesh* mesh, const std::vector<PointKey>& keys,
    const std::vector<char>& used, const OpticalProperties& material);
  /// Collective: this rank's physical triangles' eta and mu_t' (4 each).
  std::vector<double> TriangleValues(const TetMesh* mesh, const OpticalProperties& material) const;
  /// Collective: the surface triangles' eta and mu_t' again when they
  /// changed on some rank; returns whether they did.
  bool RefreshValues(MPI_Comm comm, const TetMesh* mesh, const OpticalProperties& material);
  /// Collective: the beams' power entering the object (W per channel).
  std::array<double, NumberOfChannels> Entering(
    MPI_Comm comm, const std::vector<LightSource>& beams, bool shadows) const;
  /// Collective: the loads' power sums and what the ranks' loads did.
  void SumOverRanks(MPI_Comm comm, bool raysCast, CollimatedSource& out);

  bool Valid_ = false;
  bool Gathered_ = false;
  bool ValuesGathered_ = false;
  std::uint64_t Revision_ = 0;
  std::vector<PointKey> Keys_;
  BoundarySurface Surface_;
  std::vector<double> Extinction_;   ///< 3 per surface triangle
  std::vector<double> PointArea_;    ///< per surface point: S_p
  std::vector<double> PointNormal_;  ///< 3 per surface point: outward unit normal
  std::vector<int> SurfacePoint_;    ///< per local point: its surface point, -1 if none
  std::vector<double> Rotations_;    ///< per surface point (unused: no uniform light here)
  std::vector<int> MyTriangles_;     ///< this rank's gathered triangles (local indices)
  std::vector<double> MyValues_;     ///< their eta and mu_t' as last gathered (4 each)

  // The rays and the field of the last Compute (while Valid_).
  bool RaysValid_ = false;
  bool RayShadows_ = false;
  std::vector<LightSource> RayBeams_;          ///< the beams the field is of
  std::vector<std::vector<int>> Entries_;      ///< per beam and local point: entry triangle
  std::vector<double> Fluence_;                ///< E_c summed over the beams, 3 per local point
  std::array<double, NumberOfChannels> Entering_{};
  CollimatedLoadCache Loads_;                  ///< this rank's tets' loads and the beams

  const char* LastUpdate_ = "full";
  long long TetsIntegrated_ = 0;
  double GatherMs_ = 0.0, RayMs_ = 0.0, LoadMs_ = 0.0, EnteringMs_ = 0.0;
};

} // namespace translucency
