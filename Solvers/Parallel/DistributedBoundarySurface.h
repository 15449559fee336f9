/**
 * @file DistributedBoundarySurface.h
 * @brief The physical boundary surface of a tet mesh distributed over MPI
 * ranks, gathered on every rank (for the shadow rays of the distributed
 * Surface Irradiance; Documentation/Parallel.md).
 *
 * Each rank brings the boundary triangles of its own tets; a triangle that
 * no other rank also has is physical boundary (DistributedNumbering and
 * CountSharedTriangles, as the distributed solve). The physical triangles
 * (global rows and the refractive index of their tet) and their points (row,
 * coordinates, global id) are all-gathered: every rank then holds the same
 * surface, O(N^(2/3)) of N tets, with points in global-row order and the
 * triangles in rank order. Collective: every rank calls it, a rank with an
 * empty piece too.
 */
#pragma once

#include "DistributedNumbering.h"
#include "SurfaceLightKernel.h"

#include <cstdint>
#include <vector>

namespace translucency
{

/// What GatherBoundarySurface() gathered (the same on every rank).
struct BoundarySurfaceReport
{
  long long Triangles = 0;       ///< physical boundary triangles
  long long Points = 0;          ///< their distinct points
  long long GatheredBytes = 0;   ///< bytes every rank received (the records, all ranks)
  double Milliseconds = 0.0;     ///< wall time of the numbering, counting and gather (this rank)
};

/// Half the cross product (p1 - p0) x (p2 - p0): the triangle's outward
/// normal scaled by its area; returns the area.
double TriangleHalfNormal(const double* p0, const double* p1, const double* p2, double n[3]);

/**
 * Collective.
 * @param points this rank's points, 3 each (mm)
 * @param keys one per point (PointKeyFromId / PointKeyFromCoordinates)
 * The uniform light's sample rotation of a point (`rotations`) is
 *   UniformSampleRotation() of its coordinates, as in the serial code,
 *   whatever the keys and the partition.
 * @param used 1 per point of an owned tet of this rank
 * @param triangles this rank's boundary triangles (of its own tets; 3 local
 *   point ids each, outward as TetMesh::GetBoundaryTriangles)
 * @param triangleEta the refractive index of each triangle's tet
 * @param triangleTets each triangle's tet (this rank's numbering; for messages)
 * @param surface output: the physical boundary (surface.Diagonal: the
 *   bounding box diagonal of every rank's points)
 * @param surfacePoint output: per local point, its index in surface.Points
 *   (-1: not on the physical boundary)
 * @param rotations output: per surface point, its uniform-light rotation
 * @param triangleData, valuesPerTriangle, gatheredData optional: more values
 *   of each local triangle (valuesPerTriangle each, e.g. the extinction of
 *   its tet for the collimated beam), gathered with the physical triangles
 *   into gatheredData, in surface.Triangles' order
 * @param gatheredTriangles optional output: this rank's triangles among
 *   the gathered ones (indices into `triangles`), in the order they were
 *   sent: this rank's part of surface.Triangles, which comes after the
 *   lower ranks' parts (a caller may gather new values of them alone in
 *   this order, DistributedCollimatedSource)
 * Throws translucency::Error, with the same message on every rank, for a
 * triangle held by more than two ranks (overlapping pieces without ghost
 * marks) or an invalid refractive index under a physical triangle.
 */
void GatherBoundarySurface(MPI_Comm comm, const std::vector<double>& points,
  const std::vector<PointKey>& keys, const std::vector<char>& used,
  const std::vector<int>& triangles, const std::vector<double>& triangleEta,
  const std::vector<int>& triangleTets, BoundarySurface& surface,
  std::vector<int>& surfacePoint, std::vector<double>& rotations,
  BoundarySurfaceReport& report, const std::vector<double>* triangleData = nullptr,
  int valuesPerTriangle = 0, std::vector<double>* gatheredData = nullptr,
  std::vector<int>* gatheredTriangles = nullptr);

/// A rank's part of the physical boundary (FindPieceBoundary()).
struct PieceBoundary
{
  std::vector<char> Physical;      ///< per local triangle: 1 if no other rank holds it
  std::vector<double> PointArea;   ///< per local point: S_i, mm^2 (0: not on the boundary)
  std::vector<double> PointNormal; ///< 3 per local point: outward unit normal (0 off the boundary)
  std::vector<double> PointEta;    ///< per local point: area-weighted eta of the faces around it
  std::vector<char> Owned;         ///< per local point on the boundary: this rank owns its row
  long long Triangles = 0;         ///< physical triangles over every rank
};

/**
 * Collective: which of this rank's boundary triangles are physical (no
 * other rank holds them), and, at every local point, the boundary measures
 * the serial TetMesh gives it: S_i (the areas of the physical triangles
 * around it), the unit normal (the normalised sum of their area vectors) and
 * the area-weighted refractive index (BoundaryPointRefractiveIndexAt),
 * summed over every rank's triangles (DistributedNumbering::SumToOwners,
 * FetchFromOwners: no surface is gathered). Arguments as
 * GatherBoundarySurface(); `gathered` names how to select the gathered path
 * (for the overlapping-pieces error). Throws translucency::Error, the same on
 * every rank, as GatherBoundarySurface().
 */
void FindPieceBoundary(MPI_Comm comm, const std::vector<double>& points,
  const std::vector<PointKey>& keys, const std::vector<char>& used,
  const std::vector<int>& triangles, const std::vector<double>& triangleEta,
  const std::vector<int>& triangleTets, const char* gathered, PieceBoundary& boundary);

} // namespace translucency
