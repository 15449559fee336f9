/**
 * @file DistributedSlabs.h
 * @brief The MPI test harness of the Parallel layer's suites that run on
 * MPI_COMM_WORLD (DistributedBeamCache, DistributedPaintRows): the ranks,
 * one whole mesh cut into x slabs (a rank per slab, the ranks above them
 * empty) and a piece's share of a whole-mesh material.
 */
#pragma once

#include "DistributedNumbering.h" // PointKey
#include "HypreSolver.h"         // EnsureHypreInitialized
#include "OpticalProperties.h"
#include "TestMeshes.h"
#include "TestRandomProblems.h"
#include "TetMesh.h"

#include <mpi.h>

#include <algorithm>
#include <memory>
#include <vector>

namespace translucency
{
namespace testing
{

inline int Rank()
{
  EnsureHypreInitialized(); // MPI too, if nobody has
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank;
}

inline int Size()
{
  EnsureHypreInitialized();
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  return size;
}

/// The whole mesh (the same on every rank) and this rank's piece of it.
struct Scene
{
  TetMesh Whole;
  OpticalProperties Material;     ///< per tet of Whole
  std::shared_ptr<TetMesh> Piece; ///< null: no tets on this rank
  std::vector<int> Tets;          ///< the piece's tets in Whole
  std::vector<int> Points;        ///< the piece's points in Whole
  std::vector<PointKey> Keys;
  std::vector<char> Used;
};

/// A jittered cube of 6 x 12^3 tets of side 5 mm, split in slabs along x
/// (by tet centroid) over `ranks` ranks (the ranks above them get no tets).
inline Scene MakeScene(int ranks)
{
  Scene s;
  const MeshData data = CubeMesh(12, 5.0, 0.2, 7);
  s.Whole.SetGeometry(data.Points, data.Tets);
  s.Material = RandomMaterial(s.Whole.GetNumberOfTets(), 31);
  const int rank = Rank();
  std::vector<int> local(static_cast<std::size_t>(s.Whole.GetNumberOfPoints()), -1);
  std::vector<int> tets;
  for (int t = 0; t < s.Whole.GetNumberOfTets(); ++t)
  {
    const int* v = s.Whole.GetTet(t);
    double x = 0.0;
    for (int k = 0; k < 4; ++k)
      x += 0.25 * s.Whole.GetPoint(v[k])[0];
    const int slab = std::min(ranks - 1, static_cast<int>(x / 5.0 * ranks));
    if (slab != rank)
      continue;
    s.Tets.push_back(t);
    for (int k = 0; k < 4; ++k)
    {
      int& id = local[static_cast<std::size_t>(v[k])];
      if (id < 0)
      {
        id = static_cast<int>(s.Points.size());
        s.Points.push_back(v[k]);
      }
      tets.push_back(id);
    }
  }
  std::vector<double> points;
  for (const int p : s.Points)
  {
    const double* x = s.Whole.GetPoint(p);
    points.insert(points.end(), x, x + 3);
    s.Keys.push_back(PointKeyFromId(p));
  }
  s.Used.assign(s.Points.size(), 1);
  if (!s.Tets.empty())
  {
    s.Piece = std::make_shared<TetMesh>();
    s.Piece->SetGeometry(points, tets);
  }
  return s;
}

/// The piece's share of a whole-mesh per-point array (3 per point).
inline std::vector<double> PiecePoints(const Scene& s, const std::vector<double>& whole)
{
  std::vector<double> piece;
  for (const int p : s.Points)
    for (int c = 0; c < 3; ++c)
      piece.push_back(whole[3 * static_cast<std::size_t>(p) + c]);
  return piece;
}

/// The piece's share of a whole-mesh material.
inline OpticalProperties PieceMaterial(const Scene& s, const OpticalProperties& whole)
{
  OpticalProperties m;
  for (const int t : s.Tets)
  {
    for (int c = 0; c < 3; ++c)
    {
      m.AbsorptionCoefficient.push_back(
        whole.AbsorptionCoefficient[3 * static_cast<std::size_t>(t) + c]);
      m.ReducedScatteringCoefficient.push_back(
        whole.ReducedScatteringCoefficient[3 * static_cast<std::size_t>(t) + c]);
    }
    m.RefractiveIndex.push_back(whole.RefractiveIndex[static_cast<std::size_t>(t)]);
  }
  return m;
}

} // namespace testing
} // namespace translucency
