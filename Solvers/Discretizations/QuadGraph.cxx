#include "QuadGraph.h"

#include "BiCGSTAB.h"
#include "Error.h"
#include "Fresnel.h"
#include "SpatialOrder.h"
#include "TetMesh.h"
#include "Timer.h"
#include "TriangleGeometry.h"

#include <Eigen/Dense>

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

namespace translucency
{

namespace
{

/// Relaxation sweeps and BiCGSTAB run on several threads from this many
/// unknowns on (below, a parallel region costs more than the work).
constexpr int ParallelRows = 32768;

using Vec3 = Eigen::Vector3d;

const char* const ChannelNames[NumberOfChannels] = { "R", "G", "B" };

/// Local face k of a tet is the face opposite its vertex k.
const int FaceVertices[4][3] = { { 1, 2, 3 }, { 0, 2, 3 }, { 0, 1, 3 }, { 0, 1, 2 } };

/// BiCGSTAB restarts every this many iterations (it converges in about half
/// the iterations on these systems than without restarts).
constexpr int BiCGSTABRestart = 250;

/// Coarsening stops at this many cells (multi-level initialisation).
constexpr int CoarsestCells = 1000;

/// Cells per coarse cell.
constexpr int GroupSize = 8;

/// eq. 10: interpolation from b nearby coarse nodes (paper: b = 8 inner, 4 surface).
constexpr int InnerStencil = 8;
constexpr int SurfaceStencil = 4;

inline Vec3 At(const std::vector<double>& xyz, int i)
{
  const size_t k = 3 * static_cast<size_t>(i);
  return Vec3(xyz[k], xyz[k + 1], xyz[k + 2]);
}

/// Matrix pattern from sorted links: each row is its links with the diagonal
/// inserted in order.
void BuildPattern(QuadGraphSolver::Level& level)
{
  const int n = level.GetNumberOfNodes();
  level.RowOffsets.resize(n + 1);
  for (int i = 0; i <= n; ++i)
  {
    level.RowOffsets[i] = level.LinkOffsets[i] + i;
  }
  level.ColumnIndices.resize(level.RowOffsets[n]);
  for (int i = 0; i < n; ++i)
  {
    int k = level.RowOffsets[i];
    bool placed = false;
    for (int l = level.LinkOffsets[i]; l < level.LinkOffsets[i + 1]; ++l)
    {
      if (!placed && level.LinkNodes[l] > i)
      {
        level.ColumnIndices[k++] = i;
        placed = true;
      }
      level.ColumnIndices[k++] = level.LinkNodes[l];
    }
    if (!placed)
    {
      level.ColumnIndices[k++] = i;
    }
  }
}

/// Sort the links of every node by node id (with their lengths and areas).
void SortLinks(QuadGraphSolver::Level& level, int numThreads)
{
  const int n = level.GetNumberOfNodes();
#pragma omp parallel for schedule(static) num_threads(numThreads)
  for (int i = 0; i < n; ++i)
  {
    const int begin = level.LinkOffsets[i], end = level.LinkOffsets[i + 1];
    for (int a = begin + 1; a < end; ++a) // insertion sort: 1 to ~20 links
    {
      const int node = level.LinkNodes[a];
      const double length = level.LinkLengths[a];
      const bool areas = !level.LinkAreas.empty();
      const double area = areas ? level.LinkAreas[a] : 0.0;
      int b = a;
      for (; b > begin && level.LinkNodes[b - 1] > node; --b)
      {
        level.LinkNodes[b] = level.LinkNodes[b - 1];
        level.LinkLengths[b] = level.LinkLengths[b - 1];
        if (areas)
        {
          level.LinkAreas[b] = level.LinkAreas[b - 1];
        }
      }
      level.LinkNodes[b] = node;
      level.LinkLengths[b] = length;
      if (areas)
      {
        level.LinkAreas[b] = area;
      }
    }
  }
}

/// Per-channel coefficients of one level's nodes.
struct LevelCoefficients
{
  std::array<std::vector<double>, NumberOfChannels> CellKappa, CellMu;
  std::array<std::vector<double>, NumberOfChannels> SurfaceKappa, SurfaceRhs;
  /// Interior sources: the sources' share of each cell divided by its
  /// volume (W/mm^3), the cell's right-hand side (AddSourceLoad).
  std::array<std::vector<double>, NumberOfChannels> CellSource;
  std::vector<double> SurfaceA;

  void Resize(int cells, int surface)
  {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      CellKappa[c].assign(cells, 0.0);
      CellMu[c].assign(cells, 0.0);
      CellSource[c].assign(cells, 0.0);
      SurfaceKappa[c].assign(surface, 0.0);
      SurfaceRhs[c].assign(surface, 0.0);
    }
    SurfaceA.assign(surface, 0.0);
  }
};

/**
 * The level's system (QuadGraph, eq. 5-6), rows parallel (each row
 * writes only its own entries: the result does not depend on threads).
 */
void AssembleLevel(const QuadGraphSolver::Level& level,
  const LevelCoefficients& k,
  DiffusionSystem& system,
  int numThreads,
  bool twoPointFlux = false)
{
  twoPointFlux = twoPointFlux && !level.LinkAreas.empty();
  const int n = level.GetNumberOfNodes();
  const int numCells = level.NumberOfCells;
  system.NumberOfUnknowns = n;
  system.RowOffsets = level.RowOffsets;
  system.ColumnIndices = level.ColumnIndices;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    system.Values[c].resize(level.ColumnIndices.size());
    system.RightHandSide[c].resize(n);
  }
#pragma omp parallel for schedule(static) num_threads(numThreads)
  for (int i = 0; i < n; ++i)
  {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      double* values = system.Values[c].data();
      int pos = level.RowOffsets[i];
      int diagonalPos = -1;
      double diagonal = 0.0, rhs = 0.0;
      if (i < numCells)
      {
        rhs = k.CellSource[c][i]; // interior sources (both weightings)
      }
      if (i < numCells && twoPointFlux)
      {
        // Not the paper's eq. 5 (QuadGraphSolver::SetTwoPointFlux): the
        // two-point finite-volume balance of cell i divided by V_i,
        // sum_j T_ij (phi_i - phi_j) + mu_i phi_i = 0,
        // T_ij = kappa_ij S_ij / (V_i d_ij), kappa_ij the harmonic mean.
        const double kappaI = k.CellKappa[c][i];
        const double volume = level.CellVolumes[i];
        diagonal = k.CellMu[c][i];
        for (int l = level.LinkOffsets[i]; l < level.LinkOffsets[i + 1]; ++l)
        {
          const int j = level.LinkNodes[l];
          if (diagonalPos < 0 && j > i)
          {
            diagonalPos = pos++;
          }
          double kappa = kappaI;
          if (j < numCells)
          {
            const double kappaJ = k.CellKappa[c][j];
            kappa = 2.0 * kappaI * kappaJ / (kappaI + kappaJ);
          }
          const double weight = kappa * level.LinkAreas[l] / (volume * level.LinkLengths[l]);
          diagonal += weight;
          values[pos++] = -weight;
        }
      }
      else if (i < numCells)
      {
        // eq. 5: sum_j kappa_j phi_j / d_ij^2 - (w kappa_i + mu_i) phi_i = 0,
        // w = sum_j 1/d_ij^2; written with the opposite sign (positive diagonal).
        const double kappaI = k.CellKappa[c][i];
        diagonal = k.CellMu[c][i];
        for (int l = level.LinkOffsets[i]; l < level.LinkOffsets[i + 1]; ++l)
        {
          const int j = level.LinkNodes[l];
          if (diagonalPos < 0 && j > i)
          {
            diagonalPos = pos++;
          }
          const double weight = 1.0 / (level.LinkLengths[l] * level.LinkLengths[l]);
          const double kappaJ = j < numCells ? k.CellKappa[c][j] : k.SurfaceKappa[c][j - numCells];
          diagonal += weight * kappaI;
          values[pos++] = -weight * kappaJ;
        }
      }
      else
      {
        // eq. 6: phi_s + 2 A kappa_s (phi_s - phi_k) / d_sk = 4 q_s / (1 - Fdr).
        const int s = i - numCells;
        const int l = level.LinkOffsets[i]; // the single link, to a cell (< i)
        const double beta = 2.0 * k.SurfaceA[s] * k.SurfaceKappa[c][s] / level.LinkLengths[l];
        values[pos++] = -beta;
        diagonal = 1.0 + beta;
        rhs = k.SurfaceRhs[c][s];
      }
      if (diagonalPos < 0)
      {
        diagonalPos = pos++;
      }
      // A coarse cell without links and without absorption would give an
      // empty row: keep the system regular (coarse levels only guess).
      values[diagonalPos] = diagonal > 0.0 ? diagonal : 1.0;
      system.RightHandSide[c][i] = rhs;
    }
  }
}


/// Restrict a level's coefficients to the next coarser level: volume-weighted
/// means of kappa and mu_a over each group of cells, area-weighted means of A
/// and of the eq. 6 right-hand side over each group of surface nodes.
void RestrictCoefficients(const QuadGraphSolver::Level& fine,
  const LevelCoefficients& kf,
  const QuadGraphSolver::Level& coarse,
  LevelCoefficients& kc)
{
  kc.Resize(coarse.NumberOfCells, coarse.NumberOfSurfaceNodes);
  for (int i = 0; i < fine.NumberOfCells; ++i)
  {
    const int g = coarse.FineParents[i];
    const double v = fine.CellVolumes[i];
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      kc.CellKappa[c][g] += v * kf.CellKappa[c][i];
      kc.CellMu[c][g] += v * kf.CellMu[c][i];
      kc.CellSource[c][g] += v * kf.CellSource[c][i]; // the power: kept on every level
    }
  }
  for (int g = 0; g < coarse.NumberOfCells; ++g)
  {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      kc.CellKappa[c][g] /= coarse.CellVolumes[g];
      kc.CellMu[c][g] /= coarse.CellVolumes[g];
      kc.CellSource[c][g] /= coarse.CellVolumes[g];
    }
  }
  for (int s = 0; s < fine.NumberOfSurfaceNodes; ++s)
  {
    const int g = coarse.FineParents[fine.NumberOfCells + s] - coarse.NumberOfCells;
    const double a = fine.SurfaceAreas[s];
    kc.SurfaceA[g] += a * kf.SurfaceA[s];
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      kc.SurfaceRhs[c][g] += a * kf.SurfaceRhs[c][s];
    }
  }
  for (int g = 0; g < coarse.NumberOfSurfaceNodes; ++g)
  {
    const double a = coarse.SurfaceAreas[g];
    kc.SurfaceA[g] /= a;
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      // As on the finest level, a surface node takes kappa from its cell:
      // with kappa_s = kappa_k the matrix is an M-matrix (x = 1/kappa on
      // cells, slightly less on surface nodes, gives M x >= 0, > 0 on the
      // surface rows), so the relaxation converges on every level.
      kc.SurfaceKappa[c][g] = kc.CellKappa[c][coarse.SurfaceCells[g]];
      kc.SurfaceRhs[c][g] /= a;
    }
  }
}

/// eq. 10: fine = sum_y w_xy coarse(y) over the stored Shepard weights.
void Prolongate(
  const QuadGraphSolver::Level& coarse, const Eigen::VectorXd& x, Eigen::VectorXd& fine, int numThreads)
{
  const int n = static_cast<int>(coarse.ProlongationOffsets.size()) - 1;
  fine.resize(n);
#pragma omp parallel for schedule(static) num_threads(numThreads)
  for (int i = 0; i < n; ++i)
  {
    double sum = 0.0;
    for (int k = coarse.ProlongationOffsets[i]; k < coarse.ProlongationOffsets[i + 1]; ++k)
    {
      sum += coarse.ProlongationWeights[k] * x[coarse.ProlongationNodes[k]];
    }
    fine[i] = sum;
  }
}


/// The face topology of the tet mesh that BuildGraph's phases share.
struct FaceTopology
{
  std::vector<int> Across;             ///< per tet face (4 t + k): the tet across, or -1
  std::vector<signed char> AcrossFace; ///< that tet's local face, or -1
  std::vector<int> FaceTriangle;       ///< per tet face: its boundary triangle, or -1
  std::vector<int> NumBoundaryFaces;   ///< per tet
  std::vector<int> CellStart;          ///< per tet: its first cell (4 cells when split)

  /// The cell of tet t on its face k (the tet's only cell if not split).
  int CellOf(int t, int k) const
  {
    return CellStart[t] + (CellStart[t + 1] - CellStart[t] == 4 ? k : 0);
  }
};

/// BuildGraph, 1. The tet across each face (and that tet's local face), or -1.
void FindFaceNeighbours(const TetMesh& mesh, int numThreads, FaceTopology& topology)
{
  const int numTets = mesh.GetNumberOfTets();
  const std::vector<int>& tets = mesh.GetTets();
  const std::vector<int>& pointTetOffsets = mesh.GetPointTetOffsets();
  const std::vector<int>& pointTets = mesh.GetPointTets();
  std::vector<int>& across = topology.Across;
  std::vector<signed char>& acrossFace = topology.AcrossFace;
  across.assign(4 * static_cast<size_t>(numTets), -1);
  acrossFace.assign(4 * static_cast<size_t>(numTets), -1);
#pragma omp parallel for schedule(static) num_threads(numThreads)
  for (int t = 0; t < numTets; ++t)
  {
    const int* tv = &tets[4 * static_cast<size_t>(t)];
    for (int k = 0; k < 4; ++k)
    {
      const int a = tv[FaceVertices[k][0]], b = tv[FaceVertices[k][1]], c = tv[FaceVertices[k][2]];
      // Search the tets around the face vertex with the fewest tets.
      int p = a;
      for (int q : { b, c })
      {
        if (pointTetOffsets[q + 1] - pointTetOffsets[q] < pointTetOffsets[p + 1] - pointTetOffsets[p])
        {
          p = q;
        }
      }
      for (int m = pointTetOffsets[p]; m < pointTetOffsets[p + 1]; ++m)
      {
        const int u = pointTets[m];
        if (u == t)
        {
          continue;
        }
        const int* uv = &tets[4 * static_cast<size_t>(u)];
        int found = 0, missing = -1;
        for (int e = 0; e < 4; ++e)
        {
          if (uv[e] == a || uv[e] == b || uv[e] == c)
          {
            ++found;
          }
          else
          {
            missing = e;
          }
        }
        if (found == 3)
        {
          across[4 * static_cast<size_t>(t) + k] = u;
          acrossFace[4 * static_cast<size_t>(t) + k] = static_cast<signed char>(missing);
          break;
        }
      }
    }
  }
}

/// BuildGraph, 2. Boundary triangles: the local face of their owner tet; a
/// face neither shared nor a boundary triangle (or both) is an error.
void FindBoundaryFaces(const TetMesh& mesh, FaceTopology& topology)
{
  const int numTets = mesh.GetNumberOfTets();
  const std::vector<int>& tets = mesh.GetTets();
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  const std::vector<int>& owners = mesh.GetBoundaryTriangleTets();
  const int numTriangles = mesh.GetNumberOfBoundaryTriangles();
  const std::vector<int>& across = topology.Across;
  std::vector<int>& faceTriangle = topology.FaceTriangle;
  std::vector<int>& numBoundaryFaces = topology.NumBoundaryFaces;
  faceTriangle.assign(4 * static_cast<size_t>(numTets), -1);
  numBoundaryFaces.assign(numTets, 0);
  for (int f = 0; f < numTriangles; ++f)
  {
    const int t = owners[f];
    const int* tv = &tets[4 * static_cast<size_t>(t)];
    const int* tri = &triangles[3 * static_cast<size_t>(f)];
    int k = -1;
    for (int e = 0; e < 4; ++e)
    {
      if (tv[e] != tri[0] && tv[e] != tri[1] && tv[e] != tri[2])
      {
        k = e;
      }
    }
    faceTriangle[4 * static_cast<size_t>(t) + k] = f;
    ++numBoundaryFaces[t];
  }
  for (size_t tk = 0; tk < across.size(); ++tk)
  {
    if ((across[tk] < 0) == (faceTriangle[tk] < 0))
    {
      std::ostringstream os;
      os << "quadgraph: face " << tk % 4 << " of tet " << tk / 4
         << (across[tk] < 0 ? " has no neighbour and is no boundary triangle"
                            : " is both shared and a boundary triangle")
         << " (non-manifold mesh?)";
      throw Error(os.str());
    }
  }
}

/// BuildGraph, 3. Split tets with 2 or 3 boundary faces at their centroid
/// (paper Sec. 4.1, Fig. 4); a cell per tet of the split mesh.
void SplitCells(const TetMesh& mesh, int numThreads, FaceTopology& topology,
  QuadGraphSolver::Graph& graph)
{
  const int numTets = mesh.GetNumberOfTets();
  const int numPoints = mesh.GetNumberOfPoints();
  const std::vector<int>& tets = mesh.GetTets();
  const std::vector<double>& points = mesh.GetPoints();
  const int numTriangles = mesh.GetNumberOfBoundaryTriangles();
  QuadGraphSolver::Graph& g = graph;
  QuadGraphSolver::Level& fine = graph.Fine;
  const std::vector<int>& numBoundaryFaces = topology.NumBoundaryFaces;
  std::vector<int>& cellStart = topology.CellStart;
  cellStart.assign(numTets + 1, 0);
  for (int t = 0; t < numTets; ++t)
  {
    const bool split = numBoundaryFaces[t] >= 2;
    g.NumberOfSplitTets += split ? 1 : 0;
    cellStart[t + 1] = cellStart[t] + (split ? 4 : 1);
  }
  const int numCells = cellStart[numTets];
  fine.NumberOfCells = numCells;
  fine.NumberOfSurfaceNodes = numTriangles;
  const int numNodes = numCells + numTriangles;
  g.CellTets.resize(numCells);
  g.CellFaces.resize(numCells);
  g.SplitPoints = points;
  g.SplitPoints.resize(3 * (static_cast<size_t>(numPoints) + g.NumberOfSplitTets));
  g.SplitTets.resize(4 * static_cast<size_t>(numCells));
  fine.Positions.resize(3 * static_cast<size_t>(numNodes));
  fine.CellVolumes.resize(numCells);
  {
    int splitIndex = 0;
    for (int t = 0; t < numTets; ++t)
    {
      const int* tv = &tets[4 * static_cast<size_t>(t)];
      const int first = cellStart[t];
      if (cellStart[t + 1] - first == 1)
      {
        g.CellTets[first] = t;
        g.CellFaces[first] = -1;
        std::copy(tv, tv + 4, &g.SplitTets[4 * static_cast<size_t>(first)]);
        continue;
      }
      const int centre = numPoints + splitIndex++;
      for (int d = 0; d < 3; ++d)
      {
        double sum = 0.0;
        for (int a = 0; a < 4; ++a)
        {
          sum += points[3 * static_cast<size_t>(tv[a]) + d];
        }
        g.SplitPoints[3 * static_cast<size_t>(centre) + d] = 0.25 * sum;
      }
      for (int k = 0; k < 4; ++k)
      {
        g.CellTets[first + k] = t;
        g.CellFaces[first + k] = k;
        // Vertex k replaced by the centroid: the sub-tet on face k, with the
        // orientation of the tet.
        int* st = &g.SplitTets[4 * static_cast<size_t>(first + k)];
        std::copy(tv, tv + 4, st);
        st[k] = centre;
      }
    }
  }
#pragma omp parallel for schedule(static) num_threads(numThreads)
  for (int i = 0; i < numCells; ++i)
  {
    const int* st = &g.SplitTets[4 * static_cast<size_t>(i)];
    Vec3 centroid = Vec3::Zero();
    for (int a = 0; a < 4; ++a)
    {
      centroid += At(g.SplitPoints, st[a]);
    }
    centroid *= 0.25;
    for (int d = 0; d < 3; ++d)
    {
      fine.Positions[3 * static_cast<size_t>(i) + d] = centroid[d];
    }
    const double v = mesh.GetTetVolume(g.CellTets[i]);
    fine.CellVolumes[i] = g.CellFaces[i] < 0 ? v : 0.25 * v;
  }
}

/// BuildGraph, 4. Surface nodes: at the foot of the perpendicular from the
/// owner cell's centroid to the boundary face (the link along the face
/// normal meets the face there), q interpolated at the closest point of the
/// face.
void PlaceSurfaceNodes(
  const TetMesh& mesh, int numThreads, const FaceTopology& topology, QuadGraphSolver::Graph& graph)
{
  const std::vector<double>& points = mesh.GetPoints();
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  const std::vector<int>& owners = mesh.GetBoundaryTriangleTets();
  const int numTriangles = mesh.GetNumberOfBoundaryTriangles();
  QuadGraphSolver::Graph& g = graph;
  QuadGraphSolver::Level& fine = graph.Fine;
  const std::vector<int>& faceTriangle = topology.FaceTriangle;
  const int numCells = graph.Fine.NumberOfCells;
  auto cellOf = [&topology](int t, int k) { return topology.CellOf(t, k); };
  fine.SurfaceAreas = mesh.GetBoundaryTriangleAreas();
  fine.SurfaceCells.resize(numTriangles);
  g.SurfaceTriangles.resize(numTriangles);
  g.SurfaceWeights.resize(3 * static_cast<size_t>(numTriangles));
#pragma omp parallel for schedule(static) num_threads(numThreads)
  for (int f = 0; f < numTriangles; ++f)
  {
    const int t = owners[f];
    int k = 0;
    while (faceTriangle[4 * static_cast<size_t>(t) + k] != f)
    {
      ++k;
    }
    const int cell = cellOf(t, k);
    const int* tri = &triangles[3 * static_cast<size_t>(f)];
    const Vec3 p0 = At(points, tri[0]), p1 = At(points, tri[1]), p2 = At(points, tri[2]);
    const Vec3 normal = (p1 - p0).cross(p2 - p0).normalized(); // outward
    const Vec3 x = At(fine.Positions, cell);
    const Vec3 foot = x - (x - p0).dot(normal) * normal;
    for (int d = 0; d < 3; ++d)
    {
      fine.Positions[3 * (static_cast<size_t>(numCells) + f) + d] = foot[d];
    }
    fine.SurfaceCells[f] = cell;
    g.SurfaceTriangles[f] = f;
    // The foot lies in the face's plane; its closest point is itself
    // unless it falls outside the triangle.
    ClosestPointOnTriangle(foot, p0, p1, p2, &g.SurfaceWeights[3 * static_cast<size_t>(f)]);
  }
}

/// BuildGraph, 5. Links: four per cell (the cell or surface node across each
/// face of its split-mesh tet), one per surface node; sorted, with the
/// matrix pattern.
void BuildLinks(int numThreads, const FaceTopology& topology, QuadGraphSolver::Graph& graph)
{
  QuadGraphSolver::Graph& g = graph;
  QuadGraphSolver::Level& fine = graph.Fine;
  const std::vector<int>& across = topology.Across;
  const std::vector<signed char>& acrossFace = topology.AcrossFace;
  const std::vector<int>& faceTriangle = topology.FaceTriangle;
  const std::vector<int>& cellStart = topology.CellStart;
  const int numCells = graph.Fine.NumberOfCells;
  const int numNodes = graph.Fine.NumberOfCells + graph.Fine.NumberOfSurfaceNodes;
  auto cellOf = [&topology](int t, int k) { return topology.CellOf(t, k); };
  fine.LinkOffsets.resize(numNodes + 1);
  for (int i = 0; i <= numNodes; ++i)
  {
    fine.LinkOffsets[i] = i <= numCells ? 4 * i : 4 * numCells + (i - numCells);
  }
  fine.LinkNodes.resize(fine.LinkOffsets[numNodes]);
  fine.LinkLengths.resize(fine.LinkOffsets[numNodes]);
  fine.LinkAreas.resize(fine.LinkOffsets[numNodes]);
  auto acrossNode = [&](int t, int k)
  {
    const size_t tk = 4 * static_cast<size_t>(t) + k;
    return across[tk] >= 0 ? cellOf(across[tk], acrossFace[tk]) : numCells + faceTriangle[tk];
  };
#pragma omp parallel for schedule(static) num_threads(numThreads)
  for (int i = 0; i < numNodes; ++i)
  {
    int* link = &fine.LinkNodes[fine.LinkOffsets[i]];
    if (i >= numCells)
    {
      link[0] = fine.SurfaceCells[i - numCells];
    }
    else if (g.CellFaces[i] < 0)
    {
      for (int k = 0; k < 4; ++k)
      {
        link[k] = acrossNode(g.CellTets[i], k);
      }
    }
    else
    {
      // Sub-tet on face k: across face k, and its three siblings.
      const int t = g.CellTets[i], k = g.CellFaces[i];
      link[0] = acrossNode(t, k);
      int n = 1;
      for (int m = 0; m < 4; ++m)
      {
        if (m != k)
        {
          link[n++] = cellStart[t] + m;
        }
      }
    }
    const Vec3 x = At(fine.Positions, i);
    for (int l = fine.LinkOffsets[i]; l < fine.LinkOffsets[i + 1]; ++l)
    {
      fine.LinkLengths[l] = (At(fine.Positions, fine.LinkNodes[l]) - x).norm();
    }
    // The face each link crosses, for the two-point weights: of a cell's
    // split-mesh tet, the face opposite vertex a, where a is the link's
    // local face (unsplit: link k crosses face k; sub-tet on face k: link 0
    // crosses face k, the link to sibling m the face opposite vertex m).
    double* area = &fine.LinkAreas[fine.LinkOffsets[i]];
    if (i >= numCells)
    {
      area[0] = fine.SurfaceAreas[i - numCells];
      continue;
    }
    const int* st = &g.SplitTets[4 * static_cast<size_t>(i)];
    auto faceArea = [&](int a)
    {
      const Vec3 p0 = At(g.SplitPoints, st[FaceVertices[a][0]]);
      const Vec3 p1 = At(g.SplitPoints, st[FaceVertices[a][1]]);
      const Vec3 p2 = At(g.SplitPoints, st[FaceVertices[a][2]]);
      return 0.5 * (p1 - p0).cross(p2 - p0).norm();
    };
    if (g.CellFaces[i] < 0)
    {
      for (int a = 0; a < 4; ++a)
      {
        area[a] = faceArea(a);
      }
    }
    else
    {
      const int k = g.CellFaces[i];
      area[0] = faceArea(k);
      int n = 1;
      for (int m = 0; m < 4; ++m)
      {
        if (m != k)
        {
          area[n++] = faceArea(m);
        }
      }
    }
  }
  SortLinks(fine, numThreads);
  BuildPattern(fine);
}

/// BuildGraph, 6. Vertex map: a weighted linear least-squares fit over the
/// nodes of the cells containing each point and the surface nodes of its
/// boundary faces.
void BuildVertexMap(
  const TetMesh& mesh, int numThreads, const FaceTopology& topology, QuadGraphSolver::Graph& graph)
{
  const int numPoints = mesh.GetNumberOfPoints();
  const std::vector<int>& tets = mesh.GetTets();
  const std::vector<double>& points = mesh.GetPoints();
  const std::vector<int>& pointTetOffsets = mesh.GetPointTetOffsets();
  const std::vector<int>& pointTets = mesh.GetPointTets();
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  const int numTriangles = mesh.GetNumberOfBoundaryTriangles();
  QuadGraphSolver::Graph& g = graph;
  QuadGraphSolver::Level& fine = graph.Fine;
  const std::vector<int>& cellStart = topology.CellStart;
  const int numCells = graph.Fine.NumberOfCells;
  std::vector<int> pointTriangleOffsets(numPoints + 1, 0), pointTriangles;
  for (int f = 0; f < numTriangles; ++f)
  {
    for (int m = 0; m < 3; ++m)
    {
      ++pointTriangleOffsets[triangles[3 * static_cast<size_t>(f) + m] + 1];
    }
  }
  std::partial_sum(
    pointTriangleOffsets.begin(), pointTriangleOffsets.end(), pointTriangleOffsets.begin());
  pointTriangles.resize(pointTriangleOffsets[numPoints]);
  {
    std::vector<int> fill(pointTriangleOffsets.begin(), pointTriangleOffsets.end() - 1);
    for (int f = 0; f < numTriangles; ++f)
    {
      for (int m = 0; m < 3; ++m)
      {
        pointTriangles[fill[triangles[3 * static_cast<size_t>(f) + m]]++] = f;
      }
    }
  }
  g.VertexOffsets.assign(numPoints + 1, 0);
  for (int v = 0; v < numPoints; ++v)
  {
    int count = pointTriangleOffsets[v + 1] - pointTriangleOffsets[v];
    for (int m = pointTetOffsets[v]; m < pointTetOffsets[v + 1]; ++m)
    {
      const int t = pointTets[m];
      count += cellStart[t + 1] - cellStart[t] == 4 ? 3 : 1;
    }
    g.VertexOffsets[v + 1] = g.VertexOffsets[v] + count;
  }
  g.VertexNodes.resize(g.VertexOffsets[numPoints]);
  g.VertexWeights.resize(g.VertexOffsets[numPoints]);
#pragma omp parallel for schedule(dynamic, 256) num_threads(numThreads)
  for (int v = 0; v < numPoints; ++v)
  {
    int* nodes = &g.VertexNodes[g.VertexOffsets[v]];
    double* weights = &g.VertexWeights[g.VertexOffsets[v]];
    const int count = g.VertexOffsets[v + 1] - g.VertexOffsets[v];
    int n = 0;
    for (int m = pointTetOffsets[v]; m < pointTetOffsets[v + 1]; ++m)
    {
      const int t = pointTets[m];
      if (cellStart[t + 1] - cellStart[t] == 1)
      {
        nodes[n++] = cellStart[t];
        continue;
      }
      // Sub-tets of a split tet holding v: all but the one opposite v.
      const int* tv = &tets[4 * static_cast<size_t>(t)];
      for (int k = 0; k < 4; ++k)
      {
        if (tv[k] != v)
        {
          nodes[n++] = cellStart[t] + k;
        }
      }
    }
    for (int m = pointTriangleOffsets[v]; m < pointTriangleOffsets[v + 1]; ++m)
    {
      nodes[n++] = numCells + pointTriangles[m];
    }
    if (count == 0)
    {
      continue; // a point used by no tet: fluence 0
    }
    // Weights w_j = 1/|x_j - x_v|^2; the fit phi(x) = phibar + g.(x - xbar)
    // evaluated at x_v is sum_j phi_j w_j (1/W + (x_j - xbar).u) with
    // u = C^-1 (x_v - xbar), C = sum_j w_j (x_j - xbar)(x_j - xbar)^T.
    const Vec3 xv = At(points, v);
    double total = 0.0;
    Vec3 mean = Vec3::Zero();
    int coincident = -1;
    for (int j = 0; j < count; ++j)
    {
      const double d2 = (At(fine.Positions, nodes[j]) - xv).squaredNorm();
      if (d2 == 0.0)
      {
        coincident = j;
        break;
      }
      weights[j] = 1.0 / d2;
      total += weights[j];
      mean += weights[j] * At(fine.Positions, nodes[j]);
    }
    if (coincident >= 0)
    {
      std::fill(weights, weights + count, 0.0);
      weights[coincident] = 1.0;
      continue;
    }
    mean /= total;
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (int j = 0; j < count; ++j)
    {
      const Vec3 r = At(fine.Positions, nodes[j]) - mean;
      cov += weights[j] * r * r.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
    eigen.computeDirect(cov);
    const Vec3 lambda = eigen.eigenvalues(); // ascending
    Vec3 u = Vec3::Zero();
    if (count >= 4 && lambda[0] > 1e-3 * lambda[2])
    {
      u = eigen.eigenvectors() * (eigen.eigenvectors().transpose() * (xv - mean))
                                   .cwiseQuotient(lambda);
    }
    for (int j = 0; j < count; ++j)
    {
      weights[j] *= 1.0 / total + (At(fine.Positions, nodes[j]) - mean).dot(u);
    }
  }
}

} // namespace

struct QuadGraphSolver::Coefficients : LevelCoefficients
{
};

void QuadGraphSolver::AddSourceLoad(
  const TetMesh& mesh, const std::vector<PlacedSource>& placed, Coefficients& k) const
{
  // The transpose of the vertex map: the P1 load of the source (P times its
  // barycentric weights on the tet's vertices, the FEM load) carried to the
  // nodes by the weights through which those vertices read the nodes. A
  // cell's share enters its row as a density (share / V_i: the rows are
  // balances per unit volume); a surface node's share as a flux through its
  // face in eq. 6, like q (2A share / S_s on the right-hand side).
  const Level& fine = Graph_.Fine;
  for (const PlacedSource& source : placed)
  {
    const int* tet = mesh.GetTet(source.Tet);
    for (int a = 0; a < 4; ++a)
    {
      const int v = tet[a];
      for (int m = Graph_.VertexOffsets[v]; m < Graph_.VertexOffsets[v + 1]; ++m)
      {
        const int node = Graph_.VertexNodes[m];
        const double w = source.Weights[a] * Graph_.VertexWeights[m];
        for (int c = 0; c < NumberOfChannels; ++c)
        {
          const double share = w * source.Source.Power[c];
          if (node < fine.NumberOfCells)
          {
            k.CellSource[c][node] += share / fine.CellVolumes[node];
          }
          else
          {
            const int s = node - fine.NumberOfCells;
            k.SurfaceRhs[c][s] += 2.0 * k.SurfaceA[s] * share / fine.SurfaceAreas[s];
          }
        }
      }
    }
  }
}

QuadGraphSolver::QuadGraphSolver() = default;
QuadGraphSolver::~QuadGraphSolver() = default;

void QuadGraphSolver::Reset()
{
  Graph_ = Graph();
  System_ = DiffusionSystem();
  for (auto& x : Solution_)
  {
    x.resize(0);
  }
  GraphMesh_ = nullptr;
  GraphPoints_.clear();
  GraphTets_.clear();
  HaveSolution_ = false;
}

void QuadGraphSolver::BuildGraph(const TetMesh& mesh, int numThreads)
{
  Graph_ = Graph();
  FaceTopology topology;
  FindFaceNeighbours(mesh, numThreads, topology);
  FindBoundaryFaces(mesh, topology);
  SplitCells(mesh, numThreads, topology, Graph_);
  PlaceSurfaceNodes(mesh, numThreads, topology, Graph_);
  BuildLinks(numThreads, topology, Graph_);
  BuildVertexMap(mesh, numThreads, topology, Graph_);
}

namespace
{
/// BuildCoarseLevels: the coarse links (groups joined by a fine link, and
/// each group's surface node) and their lengths.
void CoarseLinks(const QuadGraphSolver::Level& fine, const std::vector<int>& order,
  QuadGraphSolver::Level& coarse)
{
  const int nf = fine.NumberOfCells;
  const int nc = coarse.NumberOfCells, ns = coarse.NumberOfSurfaceNodes;
  std::vector<std::vector<int>> links(nc + ns);
  for (int r = 0; r < nf; ++r)
  {
    const int i = order[r], gi = r / GroupSize;
    for (int l = fine.LinkOffsets[i]; l < fine.LinkOffsets[i + 1]; ++l)
    {
      const int j = fine.LinkNodes[l];
      if (j < nf && coarse.FineParents[j] != gi)
      {
        links[gi].push_back(coarse.FineParents[j]);
      }
    }
  }
  for (int cs = 0; cs < ns; ++cs)
  {
    links[coarse.SurfaceCells[cs]].push_back(nc + cs);
    links[nc + cs].push_back(coarse.SurfaceCells[cs]);
  }
  coarse.LinkOffsets.assign(nc + ns + 1, 0);
  for (int i = 0; i < nc + ns; ++i)
  {
    std::sort(links[i].begin(), links[i].end());
    links[i].erase(std::unique(links[i].begin(), links[i].end()), links[i].end());
    coarse.LinkOffsets[i + 1] = coarse.LinkOffsets[i] + static_cast<int>(links[i].size());
  }
  coarse.LinkNodes.resize(coarse.LinkOffsets.back());
  coarse.LinkLengths.resize(coarse.LinkOffsets.back());
  for (int i = 0; i < nc + ns; ++i)
  {
    const Vec3 x = At(coarse.Positions, i);
    for (size_t m = 0; m < links[i].size(); ++m)
    {
      const int l = coarse.LinkOffsets[i] + static_cast<int>(m);
      coarse.LinkNodes[l] = links[i][m];
      // A zero length (coincident centroids) would make the weight infinite.
      coarse.LinkLengths[l] =
        std::max((At(coarse.Positions, links[i][m]) - x).norm(), 1e-12);
    }
  }
}

/// BuildCoarseLevels, eq. 10 weights: Shepard over the b nearest coarse
/// nodes among the parent group, its neighbour groups (inner nodes, b = 8)
/// and their surface nodes (surface nodes, b = 4).
void ProlongationWeights(
  const QuadGraphSolver::Level& fine, int numThreads, QuadGraphSolver::Level& coarse)
{
  const int nf = fine.NumberOfCells;
  const int nc = coarse.NumberOfCells;
  const int nfNodes = fine.GetNumberOfNodes();
  std::vector<int> count(nfNodes);
  std::vector<std::array<int, InnerStencil>> chosen(nfNodes);
  std::vector<std::array<double, InnerStencil>> chosenWeights(nfNodes);
#pragma omp parallel for schedule(static) num_threads(numThreads)
  for (int i = 0; i < nfNodes; ++i)
  {
    const bool surface = i >= nf;
    const int parent = coarse.FineParents[i];
    const int group = surface ? coarse.SurfaceCells[parent - nc] : parent;
    const Vec3 x = At(fine.Positions, i);
    std::vector<std::pair<double, int>> candidates;
    auto consider = [&](int gi)
    {
      if (!surface)
      {
        candidates.emplace_back((At(coarse.Positions, gi) - x).squaredNorm(), gi);
        return;
      }
      // The group's surface node is its last link (ids >= nc sort last).
      const int last = coarse.LinkOffsets[gi + 1] - 1;
      if (last >= coarse.LinkOffsets[gi] && coarse.LinkNodes[last] >= nc)
      {
        const int node = coarse.LinkNodes[last];
        candidates.emplace_back((At(coarse.Positions, node) - x).squaredNorm(), node);
      }
    };
    consider(group);
    for (int l = coarse.LinkOffsets[group]; l < coarse.LinkOffsets[group + 1]; ++l)
    {
      if (coarse.LinkNodes[l] < nc)
      {
        consider(coarse.LinkNodes[l]);
      }
    }
    int b = std::min<int>(surface ? SurfaceStencil : InnerStencil,
      static_cast<int>(candidates.size()));
    std::partial_sort(candidates.begin(), candidates.begin() + b, candidates.end());
    if (candidates[0].first == 0.0)
    {
      b = 1; // coincident nodes: Shepard interpolation takes that value
    }
    count[i] = b;
    double total = 0.0;
    for (int m = 0; m < b; ++m)
    {
      chosen[i][m] = candidates[m].second;
      chosenWeights[i][m] = b == 1 ? 1.0 : 1.0 / candidates[m].first; // eq. 10: w'_xy = |n_x - n_y|^-2
      total += chosenWeights[i][m];
    }
    for (int m = 0; m < b; ++m)
    {
      chosenWeights[i][m] /= total; // eq. 10: w_xy = w'_xy / sum_y w'_xy
    }
  }
  coarse.ProlongationOffsets.assign(nfNodes + 1, 0);
  for (int i = 0; i < nfNodes; ++i)
  {
    coarse.ProlongationOffsets[i + 1] = coarse.ProlongationOffsets[i] + count[i];
  }
  coarse.ProlongationNodes.resize(coarse.ProlongationOffsets.back());
  coarse.ProlongationWeights.resize(coarse.ProlongationOffsets.back());
  for (int i = 0; i < nfNodes; ++i)
  {
    for (int m = 0; m < count[i]; ++m)
    {
      coarse.ProlongationNodes[coarse.ProlongationOffsets[i] + m] = chosen[i][m];
      coarse.ProlongationWeights[coarse.ProlongationOffsets[i] + m] = chosenWeights[i][m];
    }
  }
}

} // namespace

void QuadGraphSolver::BuildCoarseLevels(int numThreads)
{
  Graph_.Coarse.clear();
  while (true)
  {
    const Level& fine = Graph_.Coarse.empty() ? Graph_.Fine : Graph_.Coarse.back();
    const int nf = fine.NumberOfCells;
    if (nf <= CoarsestCells || Graph_.Coarse.size() >= 16)
    {
      break;
    }
    Level coarse;
    // Groups of GroupSize consecutive cells in Morton order.
    const std::vector<int> order = MortonOrder(fine.Positions.data(), static_cast<size_t>(nf));
    const int nc = (nf + GroupSize - 1) / GroupSize;
    coarse.NumberOfCells = nc;
    coarse.FineParents.resize(fine.GetNumberOfNodes());
    std::vector<double> positions(3 * static_cast<size_t>(nc), 0.0);
    coarse.CellVolumes.assign(nc, 0.0);
    for (int r = 0; r < nf; ++r)
    {
      const int i = order[r], gi = r / GroupSize;
      coarse.FineParents[i] = gi;
      const double v = fine.CellVolumes[i];
      coarse.CellVolumes[gi] += v;
      for (int d = 0; d < 3; ++d)
      {
        positions[3 * static_cast<size_t>(gi) + d] += v * fine.Positions[3 * static_cast<size_t>(i) + d];
      }
    }
    for (int gi = 0; gi < nc; ++gi)
    {
      for (int d = 0; d < 3; ++d)
      {
        positions[3 * static_cast<size_t>(gi) + d] /= coarse.CellVolumes[gi];
      }
    }
    // One coarse surface node per group that owns fine surface nodes.
    std::vector<int> groupSurface(nc, -1);
    int ns = 0;
    for (int s = 0; s < fine.NumberOfSurfaceNodes; ++s)
    {
      const int gi = coarse.FineParents[fine.SurfaceCells[s]];
      if (groupSurface[gi] < 0)
      {
        groupSurface[gi] = 0; // mark
      }
    }
    for (int gi = 0; gi < nc; ++gi)
    {
      if (groupSurface[gi] == 0)
      {
        groupSurface[gi] = ns++;
        coarse.SurfaceCells.push_back(gi);
      }
    }
    coarse.NumberOfSurfaceNodes = ns;
    coarse.SurfaceAreas.assign(ns, 0.0);
    positions.resize(3 * static_cast<size_t>(nc + ns), 0.0);
    for (int s = 0; s < fine.NumberOfSurfaceNodes; ++s)
    {
      const int cs = groupSurface[coarse.FineParents[fine.SurfaceCells[s]]];
      coarse.FineParents[nf + s] = nc + cs;
      const double a = fine.SurfaceAreas[s];
      coarse.SurfaceAreas[cs] += a;
      for (int d = 0; d < 3; ++d)
      {
        positions[3 * (static_cast<size_t>(nc) + cs) + d] +=
          a * fine.Positions[3 * (static_cast<size_t>(nf) + s) + d];
      }
    }
    for (int cs = 0; cs < ns; ++cs)
    {
      for (int d = 0; d < 3; ++d)
      {
        positions[3 * (static_cast<size_t>(nc) + cs) + d] /= coarse.SurfaceAreas[cs];
      }
    }
    coarse.Positions = std::move(positions);

    // Coarse links: groups joined by a fine link, and each group's surface node.
    CoarseLinks(fine, order, coarse);
    BuildPattern(coarse);

    // eq. 10 weights: Shepard over the b nearest coarse nodes among the
    // parent group, its neighbour groups (inner nodes, b = 8) and their
    // surface nodes (surface nodes, b = 4).
    ProlongationWeights(fine, numThreads, coarse);
    Graph_.Coarse.push_back(std::move(coarse));
  }
}

void QuadGraphSolver::ComputeFineCoefficients(const TetMesh& mesh,
  const OpticalProperties& material,
  const std::vector<double>& irradiance,
  Coefficients& k,
  int numThreads) const
{
  const Level& fine = Graph_.Fine;
  const int numCells = fine.NumberOfCells, numSurface = fine.NumberOfSurfaceNodes;
  k.Resize(numCells, numSurface);
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
#pragma omp parallel for schedule(static) num_threads(numThreads)
  for (int i = 0; i < numCells; ++i)
  {
    const int t = Graph_.CellTets[i];
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      k.CellKappa[c][i] = material.Kappa(t, c);
      k.CellMu[c][i] = material.AbsorptionCoefficient[3 * static_cast<size_t>(t) + c];
    }
  }
#pragma omp parallel for schedule(static) num_threads(numThreads)
  for (int s = 0; s < numSurface; ++s)
  {
    // kappa and eta of the surface node's tet; q barycentric on the face.
    const int t = Graph_.CellTets[fine.SurfaceCells[s]];
    const double eta = material.RefractiveIndex[t];
    const double fdr = Fresnel::DiffuseReflectance(eta);
    k.SurfaceA[s] = Fresnel::MismatchA(eta);
    const int* tri = &triangles[3 * static_cast<size_t>(Graph_.SurfaceTriangles[s])];
    const double* w = &Graph_.SurfaceWeights[3 * static_cast<size_t>(s)];
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      const double q = w[0] * irradiance[3 * static_cast<size_t>(tri[0]) + c] +
        w[1] * irradiance[3 * static_cast<size_t>(tri[1]) + c] +
        w[2] * irradiance[3 * static_cast<size_t>(tri[2]) + c];
      k.SurfaceKappa[c][s] = material.Kappa(t, c);
      k.SurfaceRhs[c][s] = 4.0 * q / (1.0 - fdr); // eq. 6, right-hand side
    }
  }
}

bool QuadGraphSolver::SolveChannel(const DiffusionSystem& system,
  int channel,
  Eigen::VectorXd& x,
  int& iterations,
  double& residual,
  bool& converged,
  double progressBase,
  double progressSpan,
  int numThreads) const
{
  // The solver of the registry (LinearSolver.h) chosen in Solve: BiCGSTAB
  // or the relaxation of eq. 8-9 (Jacobi sweeps x <- x + D^-1 (b - M x),
  // which are eq. 8 for inner rows and eq. 9 for surface rows, with the
  // 1 - Fdr of eq. 6). x is the guess (zero if it has the wrong size).
  ChannelLinearSolver& linear = *Linear_;
  linear.SetRelTol(RelTol_);
  linear.SetMaxIter(MaxIter_);
  linear.SetNumberOfThreads(system.NumberOfUnknowns >= ParallelRows ? numThreads : 1);
  if (auto* bicgstab = dynamic_cast<BiCGSTABSolver*>(&linear))
  {
    bicgstab->SetRestartInterval(BiCGSTABRestart);
  }
  linear.SetProgressCallback([this](double fraction) { return ReportProgress(fraction); });
  LinearSolveStats stats;
  const bool done =
    linear.SolveChannel(system, channel, x, true, stats, progressBase, progressSpan);
  linear.SetProgressCallback(nullptr);
  iterations = stats.Iterations;
  residual = stats.RelativeResidual;
  converged = stats.Converged;
  return done;
}

namespace
{
/// Solve's checks after the linear solver's name: RelTol, MaxIter, the
/// material and the Irradiance (3 finite values >= 0 per point).
void CheckSolveInputs(const DiffusionProblem& problem, double relTol, int maxIter)
{
  const TetMesh& mesh = *problem.Mesh;
  const int numTets = mesh.GetNumberOfTets();
  const int numPoints = mesh.GetNumberOfPoints();
  if (!(relTol > 0.0) || !std::isfinite(relTol))
  {
    std::ostringstream os;
    os << "quadgraph: RelTol is " << relTol << ": must be > 0";
    throw Error(os.str());
  }
  if (maxIter <= 0)
  {
    throw Error("quadgraph: MaxIter is " + std::to_string(maxIter) + ": must be > 0");
  }
  const OpticalProperties& material = *problem.Material;
  material.Validate(numTets);
  const std::vector<double>& q = *problem.Irradiance;
  if (q.size() != 3 * static_cast<size_t>(numPoints))
  {
    std::ostringstream os;
    os << "Irradiance has " << q.size() << " values but the mesh has " << numPoints
       << " points (" << 3 * static_cast<size_t>(numPoints) << " values expected, 3 per point)";
    throw Error(os.str());
  }
  for (size_t k = 0; k < q.size(); ++k)
  {
    if (!(std::isfinite(q[k]) && q[k] >= 0.0))
    {
      std::ostringstream os;
      os << "Irradiance of point " << k / 3 << ", channel " << ChannelNames[k % 3] << " is "
         << q[k] << " W/mm^2: must be finite and >= 0";
      throw Error(os.str());
    }
  }
}

/// Solve: the fluence at the mesh points through the vertex map (clamped at
/// 0).
void VertexFluence(const QuadGraphSolver::Graph& g,
  const std::array<Eigen::VectorXd, NumberOfChannels>& solution, int numPoints, int numThreads,
  std::vector<double>& fluence)
{
  fluence.assign(3 * static_cast<size_t>(numPoints), 0.0);
#pragma omp parallel for schedule(static) num_threads(numThreads)
  for (int v = 0; v < numPoints; ++v)
  {
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      double sum = 0.0;
      for (int k = g.VertexOffsets[v]; k < g.VertexOffsets[v + 1]; ++k)
      {
        sum += g.VertexWeights[k] * solution[c][g.VertexNodes[k]];
      }
      fluence[3 * static_cast<size_t>(v) + c] = std::max(sum, 0.0);
    }
  }
}

/// Solve's memory report: the system, 2 work vectors per channel, the
/// graph and its coarse levels.
std::size_t GraphMemoryBytes(const QuadGraphSolver::Graph& g, const DiffusionSystem& system, int n)
{
  using Level = QuadGraphSolver::Level;
  const Level& fine = g.Fine;
  std::size_t bytes = (system.RowOffsets.size() + system.ColumnIndices.size()) * sizeof(int) +
    NumberOfChannels * system.ColumnIndices.size() * sizeof(double) +
    2 * NumberOfChannels * static_cast<std::size_t>(n) * sizeof(double);
  bytes += (fine.Positions.size() + fine.LinkLengths.size() + fine.CellVolumes.size() +
             fine.SurfaceAreas.size() + g.SurfaceWeights.size() + g.VertexWeights.size() +
             g.SplitPoints.size()) *
      sizeof(double) +
    (fine.LinkOffsets.size() + fine.LinkNodes.size() + fine.SurfaceCells.size() +
      fine.RowOffsets.size() + fine.ColumnIndices.size() + g.CellTets.size() +
      g.CellFaces.size() + g.SurfaceTriangles.size() + g.SplitTets.size() +
      g.VertexOffsets.size() + g.VertexNodes.size()) *
      sizeof(int);
  for (const Level& level : g.Coarse)
  {
    bytes += (level.Positions.size() + level.LinkLengths.size() + level.CellVolumes.size() +
               level.SurfaceAreas.size() + level.ProlongationWeights.size()) *
        sizeof(double) +
      (level.LinkOffsets.size() + level.LinkNodes.size() + level.SurfaceCells.size() +
        level.FineParents.size() + level.ProlongationOffsets.size() +
        level.ProlongationNodes.size() + level.RowOffsets.size() + level.ColumnIndices.size()) *
        sizeof(int);
  }
  return bytes;
}

} // namespace

bool QuadGraphSolver::Solve(
  const DiffusionProblem& problem, std::vector<double>& fluence, SolverReport& report)
{
  if (!problem.Mesh || !problem.Material || !problem.Irradiance)
  {
    throw Error("quadgraph: the problem needs a mesh, a material and an irradiance");
  }
  RequireSurfaceCollimatedModel(problem, "quadgraph");
  const TetMesh& mesh = *problem.Mesh;
  const int numTets = mesh.GetNumberOfTets();
  const int numPoints = mesh.GetNumberOfPoints();
  if (numTets == 0)
  {
    throw Error("quadgraph: the mesh has no tetrahedra (" + std::to_string(numPoints) +
      " points, 0 tets)");
  }
  // The linear solver from the registry's non-symmetric entries (throws
  // "quadgraph: unknown linear solver 'x' (known: bicgstab, relaxation)").
  Linear_ = CreateNonSymmetricLinearSolver(LinearSolver_, "quadgraph");
  const std::string linearSolver = Linear_->GetName();
  CheckSolveInputs(problem, RelTol_, MaxIter_);
  const OpticalProperties& material = *problem.Material;
  const std::vector<double>& q = *problem.Irradiance;
  // Interior sources placed first: a source outside the object is an error
  // (Sources::Place, the vertex solvers' messages) before any work.
  std::vector<PlacedSource> placed;
  if (problem.HasInteriorSources())
  {
    placed = problem.InteriorSources->Place(mesh, material);
  }
  const int numThreads = NumberOfThreads_ > 0 ? NumberOfThreads_ : omp_get_max_threads();

  report = SolverReport();
  report.Solver = GetName();
  report.LinearSolver = linearSolver;
  auto start = Clock::now();

  // The graph depends on the geometry only: rebuild it when the mesh
  // changed. The unknowns keep their meaning (warm start) while the tets do.
  const bool sameTets = GraphMesh_ != nullptr && GraphTets_ == mesh.GetTets();
  GraphMilliseconds_ = 0.0;
  if (!sameTets || GraphPoints_ != mesh.GetPoints())
  {
    BuildGraph(mesh, numThreads);
    GraphMilliseconds_ = MillisecondsSince(start);
    GraphMesh_ = &mesh;
    GraphTets_ = mesh.GetTets();
    GraphPoints_ = mesh.GetPoints();
    if (!sameTets)
    {
      HaveSolution_ = false;
    }
  }
  GraphMesh_ = &mesh;
  const bool warm = WarmStart_ && HaveSolution_;
  const bool multiLevel = MultiLevel_ && !warm;
  if (multiLevel && Graph_.Coarse.empty())
  {
    const auto coarseStart = Clock::now();
    BuildCoarseLevels(numThreads);
    GraphMilliseconds_ += MillisecondsSince(coarseStart);
  }
  Coefficients coefficients;
  ComputeFineCoefficients(mesh, material, q, coefficients, numThreads);
  AddSourceLoad(mesh, placed, coefficients);
  AssembleLevel(Graph_.Fine, coefficients, System_, numThreads, TwoPointFlux_);
  // Coarse systems for the multi-level initialisation.
  std::vector<DiffusionSystem> coarseSystems;
  if (multiLevel)
  {
    coarseSystems.resize(Graph_.Coarse.size());
    LevelCoefficients finer = coefficients;
    for (size_t l = 0; l < Graph_.Coarse.size(); ++l)
    {
      LevelCoefficients coarser;
      RestrictCoefficients(
        l == 0 ? Graph_.Fine : Graph_.Coarse[l - 1], finer, Graph_.Coarse[l], coarser);
      AssembleLevel(Graph_.Coarse[l], coarser, coarseSystems[l], numThreads);
      finer = std::move(coarser);
    }
  }
  report.SetupMilliseconds = MillisecondsSince(start);

  start = Clock::now();
  const int n = System_.NumberOfUnknowns;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    const double base = static_cast<double>(c) / NumberOfChannels;
    if (!ReportProgress(base))
    {
      HaveSolution_ = false;
      return false;
    }
    Eigen::VectorXd& x = Solution_[c];
    if (!(warm && x.size() == n))
    {
      x.setZero(n);
      if (multiLevel && !coarseSystems.empty())
      {
        // Coarsest level from zero, then eq. 10 level by level.
        Eigen::VectorXd coarse;
        for (size_t l = coarseSystems.size(); l-- > 0;)
        {
          int it = 0;
          double res = 0.0;
          bool ok = false;
          if (!SolveChannel(coarseSystems[l], c, coarse, it, res, ok, base, 0.0, numThreads))
          {
            HaveSolution_ = false;
            return false;
          }
          Eigen::VectorXd finer;
          Prolongate(Graph_.Coarse[l], coarse, finer, numThreads);
          coarse = std::move(finer);
        }
        // A coarse level is only a guess: never start from a broken one.
        if (coarse.allFinite())
        {
          x = std::move(coarse);
        }
      }
    }
    if (!SolveChannel(System_, c, x, report.Iterations[c], report.Residual[c],
          report.Converged[c], base, 1.0 / NumberOfChannels, numThreads))
    {
      HaveSolution_ = false;
      return false;
    }
  }
  HaveSolution_ = true;

  // Fluence at the mesh points through the vertex map (clamped at 0).
  const Graph& g = Graph_;
  VertexFluence(g, Solution_, numPoints, numThreads, fluence);
  report.SolveMilliseconds = MillisecondsSince(start);

  report.NumberOfUnknowns = n;
  report.NumberOfNonZeros = static_cast<long long>(System_.ColumnIndices.size());
  std::size_t bytes = GraphMemoryBytes(g, System_, n);
  bytes += GraphPoints_.size() * sizeof(double) + GraphTets_.size() * sizeof(int); // change check
  report.MemoryBytes = bytes;
  ReportProgress(1.0);
  return true;
}

} // namespace translucency
