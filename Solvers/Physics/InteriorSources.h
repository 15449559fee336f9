/**
 * @file InteriorSources.h
 * @brief Light sources inside the object for the vertex diffusion solvers
 * (divergence, fem): isotropic point sources and pencil beams, the source
 * term S of
 *
 *   -div(kappa grad phi) + mu_a phi = S,   S = sum_k P_k delta(x - x_k),
 *
 * with the Robin boundary condition of TransCut eq. 2. P_k is in W per
 * channel, so phi is a fluence rate in W/mm^2 (per W of source when P = 1).
 * Documentation/DiffuseOptics.md has the equations, units and conventions.
 */
#pragma once

#include "OpticalProperties.h"

#include <array>
#include <functional>
#include <string>
#include <vector>

namespace translucency
{

class TetMesh;

/// An isotropic point source inside the object.
struct PointSource
{
  std::array<double, 3> Position{};                   ///< mm
  std::array<double, NumberOfChannels> Power{ 1, 1, 1 }; ///< W per channel, >= 0; default 1 W
  /// Name used in error messages; "" = "point source <k>" (1-based).
  std::string Label;
};

/**
 * A pencil beam (an infinitely thin collimated beam) entering the object at a
 * surface point. Model (Farrell, Patterson & Wilson 1992, Med. Phys. 19(4)
 * 879-888, Sec. II.A): the beam is replaced by one isotropic point source one
 * transport mean free path z0 = 1 / mu_t' = 1 / (mu_a + mu_s') below the entry
 * point along the refracted direction, of power (1 - R_sp) P, where R_sp is
 * the Fresnel reflectance at the angle of incidence (specular reflection
 * does not enter). mu_a, mu_s' and eta are those of the tet under the entry
 * point, per channel (so each channel's source may sit at its own depth).
 */
struct PencilBeam
{
  std::array<double, 3> Position{};  ///< entry point on the surface, mm
  std::array<double, 3> Direction{}; ///< direction of travel (into the object), any length > 0
  std::array<double, NumberOfChannels> Power{ 1, 1, 1 }; ///< W per channel incident, >= 0; default 1 W
  /// Name used in error messages; "" = "pencil beam <k>" (1-based).
  std::string Label;
};

/// A point source placed in the mesh: its tet and barycentric weights.
struct PlacedSource
{
  PointSource Source;  ///< position and power (W per channel) actually injected
  int Tet = -1;        ///< containing tet
  double Weights[4]{}; ///< barycentric coordinates in that tet (TetMesh::GetTet order)
};

/**
 * The interior sources of one solve (a small registry: point sources and
 * pencil beams by kind, each with a name for messages).
 */
class Sources
{
public:
  void AddPointSource(const PointSource& source) { Points_.push_back(source); }
  void AddPencilBeam(const PencilBeam& beam) { Pencils_.push_back(beam); }
  const std::vector<PointSource>& GetPointSources() const { return Points_; }
  const std::vector<PencilBeam>& GetPencilBeams() const { return Pencils_; }
  bool Empty() const { return Points_.empty() && Pencils_.empty(); }
  void Clear()
  {
    Points_.clear();
    Pencils_.clear();
  }
  void ClearPointSources() { Points_.clear(); }
  void ClearPencilBeams() { Pencils_.clear(); }

  /// Throws translucency::Error naming the source unless every position and
  /// direction is finite, every power finite and >= 0, and every direction
  /// non-zero.
  void Validate() const;

  /**
   * Every source as isotropic point sources placed in the mesh: point sources
   * as given, each pencil beam by the Farrell et al. (1992) equivalent source
   * (one per channel whose depth differs; channels with the same depth share
   * one). Throws translucency::Error naming the source and its coordinates
   * when a point source (or a pencil beam's equivalent source) is outside
   * the object, when a pencil beam's entry point is off the surface
   * (SurfaceTolerance()) or its direction does not point into the object,
   * or on invalid material values.
   */
  std::vector<PlacedSource> Place(const TetMesh& mesh, const OpticalProperties& material) const;

  /**
   * The consistent FEM load of the sources: 3 values (R, G, B, W) per mesh
   * point, sum over the placed sources of P_c lambda_a(x_k) at the 4 vertices
   * of the containing tet (the integral of S against each P1 hat function,
   * exact for a delta source). Sums to the injected power per channel.
   */
  std::vector<double> ComputeLoad(const TetMesh& mesh, const OpticalProperties& material) const;

  /// Power entering the object per channel (W): point powers plus
  /// (1 - R_sp) P of every pencil beam.
  std::array<double, NumberOfChannels> InjectedPower(
    const TetMesh& mesh, const OpticalProperties& material) const;

private:
  std::vector<PointSource> Points_;
  std::vector<PencilBeam> Pencils_;
};

/// The closest surface point of a query point.
struct SurfacePoint
{
  int Triangle = -1;                ///< boundary triangle (TetMesh numbering)
  double Weights[3]{};              ///< barycentric weights in that triangle
  std::array<double, 3> Position{}; ///< mm
  std::array<double, 3> Normal{};   ///< outward unit normal of the triangle
  double Distance = 0.0;            ///< from the query point, mm
};

/// The closest point of the mesh surface to x (brute force over the boundary
/// triangles: O(triangles) per query). Throws if the mesh has no boundary.
SurfacePoint FindSurfacePoint(const TetMesh& mesh, const double x[3]);

/// The closest point to x on the boundary triangles `include` accepts (every
/// one when `include` is empty): Triangle, Weights, Position and Distance
/// (Normal not set); Triangle -1 when none is at a finite distance. Does not
/// throw. FindSurfacePoint and the distributed search (physical faces of a
/// piece) use it.
SurfacePoint ClosestBoundaryPoint(
  const TetMesh& mesh, const double x[3], const std::function<bool(int)>& include = {});

/// Where a pencil beam enters (LocatePencilEntry).
struct PencilEntry
{
  SurfacePoint Surface;               ///< the entry point on the tessellated surface
  int Tet = -1;                       ///< the tet under it (owner of Surface.Triangle)
  std::array<double, 3> Refracted{};  ///< unit direction of travel inside (Snell, from vacuum)
  double Transmitted = 0.0;           ///< 1 - R_sp, the Fresnel transmittance at incidence
};

/**
 * The entry of a pencil beam (Sources::Place and the Monte Carlo launch):
 * the closest surface point of beam.Position, the refracted direction and
 * the transmitted fraction, with the eta of the tet under the entry point.
 * Throws translucency::Error starting with `name` when the entry point is
 * more than `tolerance` (mm) from the surface or the direction does not
 * point into the object.
 */
PencilEntry LocatePencilEntry(const TetMesh& mesh, const OpticalProperties& material,
  const PencilBeam& beam, const std::string& name, double tolerance);

/**
 * The checks and the optics of a pencil beam's entry, once for every surface
 * query (LocatePencilEntry on a mesh; the distributed solve's closest point
 * over the ranks' physical faces): `entry` is the closest surface point of
 * beam.Position (Position, Normal and Distance read), `eta` the refractive
 * index of the tet under it. Throws translucency::Error starting with `name`
 * when the entry is more than `tolerance` (mm) from the surface or the
 * direction does not point into the object; else the refracted direction
 * (Snell, from vacuum) and the Fresnel transmittance (Surface = entry, Tet
 * left -1 for the caller).
 */
PencilEntry EnterPencilBeam(const PencilBeam& beam, const std::string& name,
  const SurfacePoint& entry, double tolerance, double eta);

/// One of Farrell's equivalent point sources of a pencil beam.
struct EquivalentSource
{
  PointSource Source; ///< Power: the transmitted power of the channels at this depth
  double Depth = 0.0; ///< one transport mean free path 1 / (mu_a + mu_s'), mm
  int Channel = 0;    ///< the first channel at this depth
};

/**
 * Farrell et al. (1992)'s equivalent isotropic sources of a pencil beam
 * entered at `entry`: one per distinct depth z0 = 1 / (mu_a + mu_s') of the
 * tet under the entry (muA, muS: 3 channels each, 1/mm), at the entry point
 * plus z0 along the refracted direction, carrying Transmitted times the beam
 * power of the channels with that depth (Label = `name`). Sources::Place and
 * the distributed solve place them.
 */
std::vector<EquivalentSource> PencilEquivalentSources(const PencilBeam& beam,
  const std::string& name, const PencilEntry& entry, const double muA[3], const double muS[3]);

/// "the equivalent point source one transport mean free path (z0 mm, channel
/// c) below the entry point, at ": how placement errors name such a source.
std::string DescribeEquivalentSource(const EquivalentSource& source);

/**
 * How far a point said to be on the surface (pencil beam entry, detector) may
 * lie from the tessellated surface: half the mean boundary edge length (mm).
 * Points given on a smooth surface that the triangles approximate pass; a
 * point inside the object more than half an edge deep does not.
 */
double SurfaceTolerance(const TetMesh& mesh);
/// The same for a surface given by its triangles (`points`: 3 coordinates
/// each; `triangles`: 3 point ids each), e.g. a gathered physical boundary.
double SurfaceTolerance(const std::vector<double>& points, const std::vector<int>& triangles);

} // namespace translucency
