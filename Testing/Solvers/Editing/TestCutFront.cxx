// CutFront (issue 18): TetCut's relaxation run on the cut front gathered from
// the pieces of a partitioned mesh moves every vertex exactly as the serial
// cut of the whole mesh (same bits), and gives the serial statistics: pieces
// made by a scattered tet partition with ghost copies and a tet brought twice
// (matched by global id), and one piece holding the whole mesh matched by
// coordinates; a stroke-like curved cutter too; pieces matched by
// coordinates, and the mesh renumbered (the relaxation follows the
// coordinates, not the point ids).

#include "CutFront.h"
#include "Error.h"
#include "TestMeshes.h"
#include "TetCut.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace
{

using namespace translucency;
using translucency::testing::BoxMesh;
using translucency::testing::MeshData;

/// The box mesh with every tet positively oriented (TetCut's input contract).
MeshData OrientedBox(int nx, int ny, int nz, double jitter, std::uint64_t seed)
{
  MeshData mesh = BoxMesh(nx, ny, nz, nx, ny, nz, jitter, seed);
  for (int t = 0; t < mesh.NumberOfTets(); ++t)
  {
    const int* v = &mesh.Tets[4 * t];
    if (TetCut::SignedVolume(&mesh.Points[3 * v[0]], &mesh.Points[3 * v[1]],
          &mesh.Points[3 * v[2]], &mesh.Points[3 * v[3]]) < 0.0)
    {
      std::swap(mesh.Tets[4 * t + 2], mesh.Tets[4 * t + 3]);
    }
  }
  return mesh;
}

/// One piece: its tets (owned or a ghost copy) and its points in ascending
/// global order (the global id is the serial point id).
struct Piece
{
  std::vector<int> Global; ///< global id of each local point, ascending
  std::vector<double> Points;
  std::vector<int> Tets;
  std::vector<char> Owned;
};

Piece MakePiece(const MeshData& mesh, const std::vector<int>& tets, const std::vector<char>& owned)
{
  Piece piece;
  std::vector<int> local(mesh.NumberOfPoints(), -1);
  for (int t : tets)
  {
    for (int a = 0; a < 4; ++a)
    {
      local[mesh.Tets[4 * t + a]] = 0;
    }
  }
  for (int i = 0; i < mesh.NumberOfPoints(); ++i)
  {
    if (local[i] == 0)
    {
      local[i] = static_cast<int>(piece.Global.size());
      piece.Global.push_back(i);
      piece.Points.insert(piece.Points.end(), &mesh.Points[3 * i], &mesh.Points[3 * i] + 3);
    }
  }
  for (int t : tets)
  {
    for (int a = 0; a < 4; ++a)
    {
      piece.Tets.push_back(local[mesh.Tets[4 * t + a]]);
    }
  }
  piece.Owned = owned;
  return piece;
}

struct Outcome
{
  std::vector<double> Points; ///< per global point (the input where not kept)
  int Movable = 0, Moved = 0, Blocked = 0, Sweeps = 0;
};

Outcome Serial(const MeshData& mesh, const TetCut::SideFunction& F)
{
  std::vector<double> side(mesh.NumberOfPoints());
  for (int i = 0; i < mesh.NumberOfPoints(); ++i)
  {
    side[i] = F(&mesh.Points[3 * i]);
  }
  TetCut cut;
  cut.Cut(mesh.Points, mesh.Tets, side, F);
  Outcome out;
  out.Points = mesh.Points;
  for (std::size_t k = 0; k < cut.GetKeptPoints().size(); ++k)
  {
    std::copy_n(&cut.GetPoints()[3 * k], 3, &out.Points[3 * cut.GetKeptPoints()[k]]);
  }
  out.Movable = cut.GetNumberOfMovableVertices();
  out.Moved = cut.GetNumberOfMovedVertices();
  out.Blocked = cut.GetNumberOfBlockedVertices();
  out.Sweeps = cut.GetNumberOfSweeps();
  return out;
}

/// The per-piece path: each piece cuts without relaxation, extracts its front;
/// the fronts are added in piece order, relaxed, and every piece's kept
/// points take their new positions (written per global id; a point of
/// several pieces must get the same bits from each).
Outcome Distributed(const MeshData& mesh, const std::vector<Piece>& pieces,
  const TetCut::SideFunction& F, bool byId, std::int64_t* frontTets = nullptr)
{
  CutFront front(byId);
  std::vector<TetCut> cuts(pieces.size());
  std::vector<std::vector<double>> sides(pieces.size());
  for (std::size_t r = 0; r < pieces.size(); ++r)
  {
    const Piece& piece = pieces[r];
    std::vector<double>& side = sides[r];
    for (std::size_t i = 0; i < piece.Global.size(); ++i)
    {
      side.push_back(F(&piece.Points[3 * i]));
    }
    cuts[r].SetNumberOfIterations(0);
    cuts[r].Cut(piece.Points, piece.Tets, side, F);
    std::vector<int> points, tets;
    CutFront::ExtractFront(piece.Tets, side, cuts[r].GetKeptTets(), piece.Owned, points, tets);
    std::vector<std::int64_t> ids, tets64(tets.begin(), tets.end());
    std::vector<double> x;
    for (int p : points)
    {
      ids.push_back(piece.Global[p]);
      x.insert(x.end(), &piece.Points[3 * p], &piece.Points[3 * p] + 3);
    }
    front.Add(ids.data(), x.data(), static_cast<std::int64_t>(ids.size()), tets64.data(),
      static_cast<std::int64_t>(tets.size() / 4));
  }
  TetCut relax;
  front.Relax(relax, F);
  if (frontTets)
  {
    *frontTets = front.GetNumberOfTets();
  }
  Outcome out;
  out.Points = mesh.Points;
  std::vector<char> written(mesh.NumberOfPoints(), 0);
  for (std::size_t r = 0; r < pieces.size(); ++r)
  {
    const Piece& piece = pieces[r];
    for (int k : cuts[r].GetKeptPoints())
    {
      const int g = piece.Global[k];
      const std::int64_t f = byId ? front.Find(g) : front.Find(&piece.Points[3 * k]);
      const double* x = f >= 0 ? front.GetPosition(f) : &piece.Points[3 * k];
      if (written[g])
      {
        for (int c = 0; c < 3; ++c)
        {
          EXPECT_EQ(out.Points[3 * g + c], x[c]) << "point " << g << " differs between pieces";
        }
      }
      std::copy_n(x, 3, &out.Points[3 * g]);
      written[g] = 1;
    }
  }
  out.Movable = relax.GetNumberOfMovableVertices();
  out.Moved = relax.GetNumberOfMovedVertices();
  out.Blocked = relax.GetNumberOfBlockedVertices();
  out.Sweeps = relax.GetNumberOfSweeps();
  return out;
}

void ExpectSame(const Outcome& serial, const Outcome& distributed)
{
  ASSERT_EQ(serial.Points.size(), distributed.Points.size());
  int differing = 0;
  for (std::size_t k = 0; k < serial.Points.size(); ++k)
  {
    differing += serial.Points[k] != distributed.Points[k];
  }
  EXPECT_EQ(differing, 0) << "coordinates that differ from the serial cut";
  EXPECT_EQ(serial.Movable, distributed.Movable);
  EXPECT_EQ(serial.Moved, distributed.Moved);
  EXPECT_EQ(serial.Blocked, distributed.Blocked);
  EXPECT_EQ(serial.Sweeps, distributed.Sweeps);
}

/// Three pieces of a scattered tet partition; piece 1 also holds ghost
/// copies of some of piece 0's tets, piece 2 an unmarked copy of some (an
/// overlap: the tet must be taken once).
std::vector<Piece> Partition(const MeshData& mesh)
{
  std::vector<std::vector<int>> tets(3);
  std::vector<std::vector<char>> owned(3);
  for (int t = 0; t < mesh.NumberOfTets(); ++t)
  {
    const int r = static_cast<int>((static_cast<std::uint64_t>(t) * 2654435761u >> 7) % 3);
    tets[r].push_back(t);
    owned[r].push_back(1);
    if (r == 0 && t % 5 == 0)
    {
      tets[1].push_back(t);
      owned[1].push_back(0);
    }
    if (r == 0 && t % 7 == 0)
    {
      tets[2].push_back(t);
      owned[2].push_back(1);
    }
  }
  std::vector<Piece> pieces;
  for (int r = 0; r < 3; ++r)
  {
    pieces.push_back(MakePiece(mesh, tets[r], owned[r]));
  }
  return pieces;
}

TEST(CutFront, PiecesByIdGiveTheSerialRelaxation)
{
  const MeshData mesh = OrientedBox(9, 8, 7, 0.3, 5);
  const TetCut::SideFunction plane = [](const double* x)
  { return 0.8 * x[0] + 0.3 * x[1] + 0.2 * x[2] - 4.1; };
  const Outcome serial = Serial(mesh, plane);
  ASSERT_GT(serial.Moved, 20) << "the relaxation must move vertices for the test to mean anything";
  std::int64_t frontTets = 0;
  ExpectSame(serial, Distributed(mesh, Partition(mesh), plane, true, &frontTets));
  EXPECT_GT(frontTets, 0);
  EXPECT_LT(frontTets, mesh.NumberOfTets() / 2) << "the front is a layer, not the mesh";
}

TEST(CutFront, CurvedCutterByIdGivesTheSerialRelaxation)
{
  const MeshData mesh = OrientedBox(8, 8, 8, 0.25, 11);
  const TetCut::SideFunction sphere = [](const double* x)
  {
    const double dx = x[0] - 2.0, dy = x[1] - 3.0, dz = x[2] - 4.5;
    return 4.3 - std::sqrt(dx * dx + dy * dy + dz * dz); // removes the inside
  };
  const Outcome serial = Serial(mesh, sphere);
  ASSERT_GT(serial.Moved, 20);
  ExpectSame(serial, Distributed(mesh, Partition(mesh), sphere, true));
}

TEST(CutFront, OnePieceByCoordinatesGivesTheSerialRelaxation)
{
  // Without ids the order is the order of first appearance: one piece
  // holding the whole mesh keeps the serial order.
  const MeshData mesh = OrientedBox(7, 7, 7, 0.3, 2);
  const TetCut::SideFunction plane = [](const double* x) { return x[2] - 0.4 * x[0] - 2.3; };
  std::vector<int> all(mesh.NumberOfTets());
  for (int t = 0; t < mesh.NumberOfTets(); ++t)
  {
    all[t] = t;
  }
  const std::vector<Piece> pieces = { MakePiece(mesh, {}, {}),
    MakePiece(mesh, all, std::vector<char>(all.size(), 1)) };
  const Outcome serial = Serial(mesh, plane);
  ASSERT_GT(serial.Moved, 20);
  ExpectSame(serial, Distributed(mesh, pieces, plane, false));
}

TEST(CutFront, ScatteredPiecesByCoordinatesGiveTheSerialRelaxation)
{
  // Without ids the front's points come in the order of first appearance
  // (piece by piece), not the serial one: TetCut visits them in the order of
  // their coordinates, so the moves are still the serial ones, bit for bit.
  const MeshData mesh = OrientedBox(9, 8, 7, 0.3, 5);
  const TetCut::SideFunction plane = [](const double* x)
  { return 0.8 * x[0] + 0.3 * x[1] + 0.2 * x[2] - 4.1; };
  const Outcome serial = Serial(mesh, plane);
  ASSERT_GT(serial.Moved, 20);
  ExpectSame(serial, Distributed(mesh, Partition(mesh), plane, false));
}

TEST(CutFront, RenumberedMeshGivesTheSameRelaxation)
{
  // The serial cut of the same mesh with its points numbered in reverse
  // (and its tets in reverse order) moves every point to the same bits.
  const MeshData mesh = OrientedBox(8, 8, 8, 0.25, 11);
  const TetCut::SideFunction sphere = [](const double* x)
  {
    const double dx = x[0] - 2.0, dy = x[1] - 3.0, dz = x[2] - 4.5;
    return 4.3 - std::sqrt(dx * dx + dy * dy + dz * dz);
  };
  const int n = mesh.NumberOfPoints();
  MeshData renumbered = mesh;
  for (int i = 0; i < n; ++i)
  {
    std::copy_n(&mesh.Points[3 * i], 3, &renumbered.Points[3 * (n - 1 - i)]);
  }
  const int m = mesh.NumberOfTets();
  for (int t = 0; t < m; ++t)
  {
    for (int a = 0; a < 4; ++a)
    {
      renumbered.Tets[4 * (m - 1 - t) + a] = n - 1 - mesh.Tets[4 * t + a];
    }
  }
  const Outcome serial = Serial(mesh, sphere);
  ASSERT_GT(serial.Moved, 20);
  Outcome other = Serial(renumbered, sphere);
  std::vector<double> back(other.Points.size());
  for (int i = 0; i < n; ++i)
  {
    std::copy_n(&other.Points[3 * (n - 1 - i)], 3, &back[3 * i]);
  }
  other.Points = back;
  ExpectSame(serial, other);
}

TEST(CutFront, BadInputIsAnError)
{
  std::vector<int> points, tets;
  EXPECT_THROW(CutFront::ExtractFront({ 0, 1, 2, 3 }, { 1.0, 1.0, -1.0 }, { 0 }, {}, points, tets),
    Error);
  EXPECT_THROW(CutFront::ExtractFront({ 0, 1, 2, 3 }, { 1.0, 1.0, -1.0, 1.0 }, { 1 }, {}, points, tets),
    Error);
  CutFront front;
  const std::int64_t ids[1] = { 4 };
  const double x[3] = { 0.0, 0.0, 0.0 };
  const std::int64_t bad[4] = { 0, 0, 0, 1 };
  EXPECT_THROW(front.Add(ids, x, 1, bad, 1), Error);
}

} // namespace
