#include "TetMesh.h"

#include "Error.h"
#include "SpatialOrder.h"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <climits>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <sstream>
#include <utility>

namespace translucency
{

namespace
{

/// Local vertices of the face opposite local vertex f, ordered so that for a
/// positively oriented tet the normal (p1-p0)x(p2-p0) points out of the tet.
constexpr int FaceVertices[4][3] = { { 1, 2, 3 }, { 0, 3, 2 }, { 0, 1, 3 }, { 0, 2, 1 } };

/// Tets per chunk of the scatter schedule: large chunks keep the scatter
/// cache-friendly (fewer rows shared between chunks of different colours),
/// small ones give each colour enough chunks to balance the threads. About
/// 256 chunks in all, within [256, 8192] tets each.
int ScatterChunkSize(int numTets)
{
  return std::clamp(numTets / 256, 256, 8192);
}

inline void Sub(const double* a, const double* b, double* r)
{
  r[0] = a[0] - b[0];
  r[1] = a[1] - b[1];
  r[2] = a[2] - b[2];
}

inline void Cross(const double* a, const double* b, double* r)
{
  r[0] = a[1] * b[2] - a[2] * b[1];
  r[1] = a[2] * b[0] - a[0] * b[2];
  r[2] = a[0] * b[1] - a[1] * b[0];
}

inline double Dot(const double* a, const double* b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/// Signed volume of the tet (p0, p1, p2, p3) (mm^3).
inline double SignedVolume(const double* p0, const double* p1, const double* p2, const double* p3)
{
  double e1[3], e2[3], e3[3], c[3];
  Sub(p1, p0, e1);
  Sub(p2, p0, e2);
  Sub(p3, p0, e3);
  Cross(e2, e3, c);
  return Dot(e1, c) / 6.0;
}

/// Morton codes of the tet centroids (tets assumed validated).
std::vector<std::uint64_t> CentroidCodes(const MortonEncoder& encode,
  const std::vector<double>& points,
  const std::vector<int>& tets)
{
  const int numTets = static_cast<int>(tets.size() / 4);
  std::vector<std::uint64_t> codes(numTets);
#pragma omp parallel for schedule(static)
  for (int t = 0; t < numTets; ++t)
  {
    double c[3] = { 0.0, 0.0, 0.0 };
    for (int a = 0; a < 4; ++a)
    {
      const double* p = &points[3 * static_cast<size_t>(tets[4 * static_cast<size_t>(t) + a])];
      c[0] += 0.25 * p[0];
      c[1] += 0.25 * p[1];
      c[2] += 0.25 * p[2];
    }
    codes[t] = encode(c);
  }
  return codes;
}

/// Bounding box diagonal length of the points (mm).
double BoundingBoxDiagonal(const std::vector<double>& points)
{
  const size_t n = points.size() / 3;
  if (n == 0)
  {
    return 0.0;
  }
  double lo[3] = { points[0], points[1], points[2] };
  double hi[3] = { points[0], points[1], points[2] };
  for (size_t i = 1; i < n; ++i)
  {
    for (int d = 0; d < 3; ++d)
    {
      lo[d] = std::min(lo[d], points[3 * i + d]);
      hi[d] = std::max(hi[d], points[3 * i + d]);
    }
  }
  const double dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

/// Throw unless every coordinate is finite; names the first bad point.
void CheckPointsFinite(const std::vector<double>& points)
{
  if (points.size() % 3 != 0)
  {
    std::ostringstream os;
    os << "the point array has " << points.size() << " values: expected 3 (x, y, z) per point";
    throw Error(os.str());
  }
  if (points.size() / 3 > static_cast<size_t>(INT_MAX))
  {
    throw Error("too many points for 32-bit ids: " + std::to_string(points.size() / 3));
  }
  const long long n = static_cast<long long>(points.size() / 3);
  long long first = LLONG_MAX;
#pragma omp parallel for reduction(min : first) schedule(static)
  for (long long i = 0; i < n; ++i)
  {
    if (!(std::isfinite(points[3 * i]) && std::isfinite(points[3 * i + 1]) &&
          std::isfinite(points[3 * i + 2])) &&
      i < first)
    {
      first = i;
    }
  }
  if (first != LLONG_MAX)
  {
    std::ostringstream os;
    os << "point " << first << " has a non-finite coordinate (" << points[3 * first] << ", "
       << points[3 * first + 1] << ", " << points[3 * first + 2] << ")";
    throw Error(os.str());
  }
}

/// Throw unless every tet has 4 distinct ids in [0, numPoints).
void CheckTetIds(const std::vector<int>& tets, int numPoints)
{
  if (tets.size() % 4 != 0)
  {
    std::ostringstream os;
    os << "the tet array has " << tets.size() << " ids: expected 4 per tet";
    throw Error(os.str());
  }
  // The point -> tet incidence lists (4 entries per tet) use int offsets.
  if (tets.size() > static_cast<size_t>(INT_MAX))
  {
    throw Error("too many tets for 32-bit offsets: " + std::to_string(tets.size() / 4) +
      " (at most " + std::to_string(INT_MAX / 4) + ")");
  }
  const long long numTets = static_cast<long long>(tets.size() / 4);
  long long firstRange = LLONG_MAX, firstRepeat = LLONG_MAX;
#pragma omp parallel for reduction(min : firstRange, firstRepeat) schedule(static)
  for (long long t = 0; t < numTets; ++t)
  {
    const int* v = &tets[4 * t];
    bool inRange = true;
    for (int a = 0; a < 4; ++a)
    {
      inRange = inRange && v[a] >= 0 && v[a] < numPoints;
    }
    if (!inRange)
    {
      firstRange = std::min(firstRange, t);
    }
    else if (v[0] == v[1] || v[0] == v[2] || v[0] == v[3] || v[1] == v[2] || v[1] == v[3] ||
      v[2] == v[3])
    {
      firstRepeat = std::min(firstRepeat, t);
    }
  }
  if (firstRange != LLONG_MAX && firstRange <= firstRepeat)
  {
    const int* v = &tets[4 * firstRange];
    for (int a = 0; a < 4; ++a)
    {
      if (v[a] < 0 || v[a] >= numPoints)
      {
        std::ostringstream os;
        os << "tet " << firstRange << " has vertex id " << v[a] << " but the mesh has " << numPoints
           << " points";
        throw Error(os.str());
      }
    }
  }
  if (firstRepeat != LLONG_MAX)
  {
    const int* v = &tets[4 * firstRepeat];
    std::ostringstream os;
    os << "tet " << firstRepeat << " repeats a vertex id: vertices " << v[0] << ", " << v[1] << ", "
       << v[2] << ", " << v[3];
    throw Error(os.str());
  }
}


/// A boundary face found at its smallest vertex, keyed by its two other
/// vertices (BuildTopology).
struct FaceEntry
{
  int Lo, Hi, Tet, Face;
  bool operator<(const FaceEntry& o) const
  {
    return Lo != o.Lo ? Lo < o.Lo : (Hi != o.Hi ? Hi < o.Hi : Tet < o.Tet);
  }
};

/// BuildTopology: throws the error for a face of `mesh` shared by more than
/// two tets, the one with the smallest vertex `badVertex` (deterministic),
/// naming the tets.
void ThrowNonManifoldFace(const TetMesh& mesh, int badVertex)
{
  const std::vector<int>& pointTetOffsets = mesh.GetPointTetOffsets();
  const std::vector<int>& pointTets = mesh.GetPointTets();
  std::vector<FaceEntry> faces;
  for (int k = pointTetOffsets[badVertex]; k < pointTetOffsets[badVertex + 1]; ++k)
  {
    const int t = pointTets[k];
    const int* tv = mesh.GetTet(t);
    for (int f = 0; f < 4; ++f)
    {
      const int* fv = FaceVertices[f];
      const int a = tv[fv[0]], b = tv[fv[1]], c = tv[fv[2]];
      if ((a == badVertex || b == badVertex || c == badVertex) &&
        std::min({ a, b, c }) == badVertex)
      {
        const int o1 = a == badVertex ? b : a;
        const int o2 = c == badVertex ? b : c;
        faces.push_back({ std::min(o1, o2), std::max(o1, o2), t, f });
      }
    }
  }
  std::sort(faces.begin(), faces.end());
  for (size_t s = 0; s < faces.size();)
  {
    size_t e = s + 1;
    while (e < faces.size() && faces[e].Lo == faces[s].Lo && faces[e].Hi == faces[s].Hi)
    {
      ++e;
    }
    if (e - s > 2)
    {
      std::ostringstream os;
      os << "face (" << badVertex << ", " << faces[s].Lo << ", " << faces[s].Hi
         << ") is shared by " << e - s << " tets (";
      for (size_t k = s; k < e; ++k)
      {
        os << (k == s ? "tet " : ", tet ") << faces[k].Tet;
      }
      os << "): a face can belong to at most two tets";
      throw Error(os.str());
    }
    s = e;
  }
}

/// The per-thread outputs of BuildTopology's adjacency pass (threads own
/// contiguous vertex ranges: concatenated in thread order they do not
/// depend on the thread count).
struct TopologyScratch
{
  explicit TopologyScratch(int maxThreads, int numPoints)
    : BoundaryPerThread(maxThreads)
    , FirstNonManifold(maxThreads, INT_MAX)
    , ColumnsPerThread(maxThreads)
    , FirstPointOfThread(maxThreads, -1)
    , RowCount(numPoints, 0)
  {
  }
  std::vector<std::vector<std::pair<int, int>>> BoundaryPerThread; ///< (tet, face)
  std::vector<int> FirstNonManifold; ///< smallest vertex of a face in > 2 tets
  std::vector<std::vector<int>> ColumnsPerThread;
  std::vector<int> FirstPointOfThread;
  std::vector<int> RowCount;
};

/// BuildTopology, 1. (inside its parallel region: orphaned worksharing)
/// point -> tets incidence of `tets`, tets ascending in each list;
/// `counts`: maxThreads x points.
void CountPointTetsInParallel(const std::vector<int>& tets, int numPoints,
  std::vector<int>& pointTetOffsets, std::vector<int>& pointTets, std::vector<int>& counts)
{
  const int numTets = static_cast<int>(tets.size() / 4);
  const int tid = omp_get_thread_num();
  const int numThreads = omp_get_num_threads();

  // 1. Point -> tets incidence, tets ascending in each list: a counting
  //    sort in which each thread counts, then places, the tets of its own
  //    contiguous range (thread ranges in increasing order).
  int* count = counts.data() + static_cast<size_t>(tid) * numPoints; // no &v[k] of an empty vector
  std::fill(count, count + numPoints, 0);
  const int tetBegin = static_cast<int>(static_cast<long long>(numTets) * tid / numThreads);
  const int tetEnd = static_cast<int>(static_cast<long long>(numTets) * (tid + 1) / numThreads);
  for (size_t k = 4 * static_cast<size_t>(tetBegin); k < 4 * static_cast<size_t>(tetEnd); ++k)
  {
    ++count[tets[k]];
  }
#pragma omp barrier
#pragma omp for schedule(static)
  for (int i = 0; i < numPoints; ++i)
  {
    int total = 0;
    for (int s = 0; s < numThreads; ++s)
    {
      total += counts[static_cast<size_t>(s) * numPoints + i];
    }
    pointTetOffsets[i + 1] = total;
  }
#pragma omp single
  for (int i = 0; i < numPoints; ++i)
  {
    pointTetOffsets[i + 1] += pointTetOffsets[i];
  }
  // Cursor of thread tid for point i: the list start plus the incidences
  // of the lower threads.
#pragma omp for schedule(static)
  for (int i = 0; i < numPoints; ++i)
  {
    int cursor = pointTetOffsets[i];
    for (int s = 0; s < numThreads; ++s)
    {
      const int c = counts[static_cast<size_t>(s) * numPoints + i];
      counts[static_cast<size_t>(s) * numPoints + i] = cursor;
      cursor += c;
    }
  }
  for (int t = tetBegin; t < tetEnd; ++t)
  {
    for (int a = 0; a < 4; ++a)
    {
      pointTets[count[tets[4 * static_cast<size_t>(t) + a]]++] = t;
    }
  }
#pragma omp barrier
}

/// BuildTopology, 2. (inside its parallel region: orphaned worksharing)
/// boundary faces and the adjacency rows, per thread.
void CollectRowsInParallel(const std::vector<int>& tets, const std::vector<int>& pointTetOffsets,
  const std::vector<int>& pointTets, std::vector<int>& diagonalPositions,
  TopologyScratch& scratch)
{
  const int numPoints = static_cast<int>(pointTetOffsets.size()) - 1;
  const int tid = omp_get_thread_num();
  std::vector<int>& firstNonManifold = scratch.FirstNonManifold;
  std::vector<int>& firstPointOfThread = scratch.FirstPointOfThread;
  std::vector<int>& rowCount = scratch.RowCount;
  // 2. Boundary faces and the adjacency rows (sorted, unique, diagonal
  //    included). The faces of v are those in which v is the smallest
  //    vertex: keyed by their two other vertices (lo, hi), collected
  //    branch-free while the row is gathered, then counted in a small
  //    (row length)^2 table indexed by the ranks of lo and hi in the sorted
  //    row; a face seen once is on the boundary, more than twice is an
  //    error. (The comparisons of vertex ids are unpredictable, so the code
  //    selects and masks instead of branching.)
  struct FaceCandidate
  {
    int Lo, Hi, Tet, Opposite;
  };
  std::vector<FaceCandidate> candidates;
  std::vector<FaceEntry> boundaryFaces;
  std::vector<int> row;
  // mark[u] == v: u is already in row v; rank[u]: index of u in the sorted
  // row of the current v; counts: the face table, zero between vertices.
  std::vector<int> mark(static_cast<size_t>(numPoints), -1);
  std::vector<int> rank(static_cast<size_t>(numPoints));
  std::vector<std::uint16_t> counts;
  auto& boundary = scratch.BoundaryPerThread[tid];
  auto& columns = scratch.ColumnsPerThread[tid];
#pragma omp for schedule(static)
  for (int v = 0; v < numPoints; ++v)
  {
    if (firstPointOfThread[tid] < 0)
    {
      firstPointOfThread[tid] = v;
    }
    const int tetBegin = pointTetOffsets[v], tetEnd = pointTetOffsets[v + 1];
    // Row of v: every vertex of its tets once (marker array, branch-free:
    // always store, advance only for a vertex not yet in the row).
    const size_t numTetsOfV = static_cast<size_t>(tetEnd - tetBegin);
    if (row.size() < 4 * numTetsOfV + 1)
    {
      row.resize(4 * numTetsOfV + 1);
    }
    // Up to 3 faces per tet, plus one slot for the masked writes.
    if (candidates.size() < 3 * numTetsOfV + 1)
    {
      candidates.resize(3 * numTetsOfV + 1);
    }
    int length = 1;
    row[0] = v;
    mark[v] = v;
    int numCandidates = 0;
    for (int k = tetBegin; k < tetEnd; ++k)
    {
      const int t = pointTets[k];
      const int* tv = &tets[4 * static_cast<size_t>(t)];
      for (int b = 0; b < 4; ++b)
      {
        const int u = tv[b];
        row[length] = u;
        length += mark[u] != v ? 1 : 0;
        mark[u] = v;
      }
      // Sorted vertices s0 < s1 < s2 < s3 (sorting network). If v = s0, its
      // faces are (s1, s2), (s1, s3), (s2, s3), opposite s3, s2, s1; if
      // v = s1, the face (s2, s3) opposite s0; otherwise none.
      int s0 = std::min(tv[0], tv[1]), s1 = std::max(tv[0], tv[1]);
      int s2 = std::min(tv[2], tv[3]), s3 = std::max(tv[2], tv[3]);
      const int lowest = std::min(s0, s2), highest = std::max(s1, s3);
      const int m1 = std::max(s0, s2), m2 = std::min(s1, s3);
      s0 = lowest;
      s1 = std::min(m1, m2);
      s2 = std::max(m1, m2);
      s3 = highest;
      const int first = v == s0 ? 1 : 0;
      const int second = v == s1 ? 1 : 0;
      candidates[numCandidates] = { s2, s3, t, first ? s1 : s0 };
      numCandidates += first | second;
      candidates[numCandidates] = { s1, s2, t, s3 };
      numCandidates += first;
      candidates[numCandidates] = { s1, s3, t, s2 };
      numCandidates += first;
    }
    int* const rowBegin = row.data();
    int* const rowEnd = rowBegin + length;
    std::sort(rowBegin, rowEnd); // unique already
    for (int k = 0; k < length; ++k)
    {
      rank[rowBegin[k]] = k;
    }
    const size_t tableSize = static_cast<size_t>(length) * static_cast<size_t>(length);
    if (counts.size() < tableSize)
    {
      counts.assign(tableSize, 0);
    }
    for (int c = 0; c < numCandidates; ++c)
    {
      const FaceCandidate& f = candidates[c];
      ++counts[static_cast<size_t>(rank[f.Lo]) * length + rank[f.Hi]];
    }
    // Read and reset the table: the first candidate of a key sees its
    // count, later ones see 0.
    boundaryFaces.clear();
    for (int c = 0; c < numCandidates; ++c)
    {
      const FaceCandidate& f = candidates[c];
      std::uint16_t& count = counts[static_cast<size_t>(rank[f.Lo]) * length + rank[f.Hi]];
      if (count == 1)
      {
        const int* tv = &tets[4 * static_cast<size_t>(f.Tet)];
        const int face = tv[0] == f.Opposite ? 0 : (tv[1] == f.Opposite ? 1 : (tv[2] == f.Opposite ? 2 : 3));
        boundaryFaces.push_back({ f.Lo, f.Hi, f.Tet, face });
      }
      else if (count > 2 && firstNonManifold[tid] == INT_MAX)
      {
        firstNonManifold[tid] = v;
      }
      count = 0;
    }
    // Boundary faces of v in (lo, hi) order (as a sort of all faces would
    // give).
    std::sort(boundaryFaces.begin(), boundaryFaces.end());
    for (const FaceEntry& e : boundaryFaces)
    {
      boundary.emplace_back(e.Tet, e.Face);
    }
    diagonalPositions[v] = rank[v];
    rowCount[v] = length;
    columns.insert(columns.end(), rowBegin, rowEnd);
  }
}

} // namespace

namespace
{
/// Process-wide unique geometry revisions (never 0).
std::uint64_t NextGeometryRevision()
{
  static std::atomic<std::uint64_t> counter{ 0 };
  return ++counter;
}
}

void TetMesh::SetGeometry(std::vector<double> points, std::vector<int> tets)
{
  CheckPointsFinite(points);
  CheckTetIds(tets, static_cast<int>(points.size() / 3));

  // Build into a fresh mesh so that *this is unchanged if anything throws.
  TetMesh mesh;
  mesh.Points_ = std::move(points);
  mesh.Tets_ = std::move(tets);
  mesh.ComputeTetVolumes(true);
  mesh.BuildTopology();
  mesh.ComputeMeasures();
  mesh.GeometryRevision_ = NextGeometryRevision();
  *this = std::move(mesh);
}

void TetMesh::UpdatePoints(const std::vector<double>& points)
{
  if (points.size() != Points_.size())
  {
    std::ostringstream os;
    os << "UpdatePoints: " << points.size() / 3 << " points given but the mesh has "
       << GetNumberOfPoints();
    throw Error(os.str());
  }
  CheckPointsFinite(points);
  std::vector<double> previous = Points_;
  Points_ = points;
  try
  {
    ComputeTetVolumes(false);
  }
  catch (...)
  {
    Points_.swap(previous);
    throw;
  }
  ComputeMeasures();
  GeometryRevision_ = NextGeometryRevision();
}

void TetMesh::ComputeTetVolumes(bool allowReorient)
{
  const int numTets = GetNumberOfTets();
  const double diagonal = BoundingBoxDiagonal(Points_);
  const double threshold = 1e-14 * diagonal * diagonal * diagonal;
  std::vector<double> volumes(numTets);
  int firstDegenerate = INT_MAX, firstInverted = INT_MAX;
#pragma omp parallel for reduction(min : firstDegenerate, firstInverted) schedule(static)
  for (int t = 0; t < numTets; ++t)
  {
    int* v = &Tets_[4 * static_cast<size_t>(t)];
    const double vol = SignedVolume(GetPoint(v[0]), GetPoint(v[1]), GetPoint(v[2]), GetPoint(v[3]));
    if (!(std::abs(vol) > threshold))
    {
      firstDegenerate = std::min(firstDegenerate, t);
    }
    else if (vol < 0.0)
    {
      if (allowReorient)
      {
        std::swap(v[2], v[3]);
      }
      else
      {
        firstInverted = std::min(firstInverted, t);
      }
    }
    volumes[t] = std::abs(vol);
  }
  auto describe = [&](int t, const char* what)
  {
    const int* v = GetTet(t);
    const double vol = SignedVolume(GetPoint(v[0]), GetPoint(v[1]), GetPoint(v[2]), GetPoint(v[3]));
    std::ostringstream os;
    os << "tet " << t << " is " << what << " (volume " << vol << " mm^3): vertices " << v[0] << ", "
       << v[1] << ", " << v[2] << ", " << v[3];
    return os.str();
  };
  if (firstDegenerate != INT_MAX && firstDegenerate <= firstInverted)
  {
    throw Error(describe(firstDegenerate, "degenerate"));
  }
  if (firstInverted != INT_MAX)
  {
    throw Error(describe(firstInverted, "inverted by the point update"));
  }
  TetVolumes_ = std::move(volumes);
}

void TetMesh::BuildTopology()
{
  const int numPoints = GetNumberOfPoints();
  const int maxThreads = omp_get_max_threads();

  // Face keys are grouped by their smallest vertex: vertex v matches the
  // faces of its tets in which it is the smallest id. Threads own contiguous
  // vertex ranges (static schedule), so concatenating their outputs in thread
  // order gives a result independent of the thread count.
  TopologyScratch scratch(maxThreads, numPoints);
  std::vector<std::vector<std::pair<int, int>>>& boundaryPerThread = scratch.BoundaryPerThread;
  std::vector<int>& firstNonManifold = scratch.FirstNonManifold;
  std::vector<std::vector<int>>& columnsPerThread = scratch.ColumnsPerThread;
  std::vector<int>& firstPointOfThread = scratch.FirstPointOfThread;
  std::vector<int>& rowCount = scratch.RowCount;
  DiagonalPositions_.resize(numPoints);
  PointTetOffsets_.assign(static_cast<size_t>(numPoints) + 1, 0);
  PointTets_.resize(Tets_.size());
  // counts[tid * numPoints + i]: incidences of point i in the tets of
  // thread tid's static range.
  std::vector<int> counts(static_cast<size_t>(maxThreads) * numPoints);

#pragma omp parallel
  {
    // The two passes share one thread team (their loops are orphaned
    // worksharing constructs of this region).
    CountPointTetsInParallel(Tets_, numPoints, PointTetOffsets_, PointTets_, counts);
    CollectRowsInParallel(Tets_, PointTetOffsets_, PointTets_, DiagonalPositions_, scratch);
  }

  // A face shared by more than two tets: report the one with the smallest
  // vertex (deterministic), naming the tets.
  const int badVertex = *std::min_element(firstNonManifold.begin(), firstNonManifold.end());
  if (badVertex != INT_MAX)
  {
    ThrowNonManifoldFace(*this, badVertex);
  }

  // Boundary triangles, outward (tets are positively oriented here).
  size_t numBoundary = 0;
  for (const auto& b : boundaryPerThread)
  {
    numBoundary += b.size();
  }
  BoundaryTriangles_.resize(3 * numBoundary);
  BoundaryTriangleTets_.resize(numBoundary);
  {
    size_t k = 0;
    for (const auto& b : boundaryPerThread)
    {
      for (const auto& [t, f] : b)
      {
        const int* tv = GetTet(t);
        for (int m = 0; m < 3; ++m)
        {
          BoundaryTriangles_[3 * k + m] = tv[FaceVertices[f][m]];
        }
        BoundaryTriangleTets_[k] = t;
        ++k;
      }
    }
  }

  // 3. CSR pattern: offsets, then every thread copies its rows.
  RowOffsets_.assign(static_cast<size_t>(numPoints) + 1, 0);
  for (int i = 0; i < numPoints; ++i)
  {
    const long long next = static_cast<long long>(RowOffsets_[i]) + rowCount[i];
    if (next > INT_MAX)
    {
      throw Error("the vertex adjacency has more than 2^31 entries: mesh too large");
    }
    RowOffsets_[i + 1] = static_cast<int>(next);
  }
  ColumnIndices_.resize(RowOffsets_[numPoints]);
#pragma omp parallel
  {
    const int tid = omp_get_thread_num();
    if (firstPointOfThread[tid] >= 0)
    {
      std::copy(columnsPerThread[tid].begin(),
        columnsPerThread[tid].end(),
        ColumnIndices_.begin() + RowOffsets_[firstPointOfThread[tid]]);
    }
    std::vector<int>().swap(columnsPerThread[tid]);
#pragma omp for schedule(static)
    for (int v = 0; v < numPoints; ++v)
    {
      DiagonalPositions_[v] += RowOffsets_[v];
    }
  }

  BuildTetNonZeroPositions();
  BuildScatterSchedule();
}

void TetMesh::BuildTetNonZeroPositions()
{
  const int numPoints = GetNumberOfPoints();
  const int numTets = GetNumberOfTets();
  TetNonZeros_.resize(16 * static_cast<size_t>(numTets));
  // Row v fills entries 4a+b of the tets where v is local vertex a (each
  // (t, a) is written once) with the position of column tv[b] in row v.
#pragma omp parallel
  {
    std::vector<int> rank(static_cast<size_t>(numPoints));
#pragma omp for schedule(static)
    for (int v = 0; v < numPoints; ++v)
    {
      for (int k = RowOffsets_[v]; k < RowOffsets_[v + 1]; ++k)
      {
        rank[ColumnIndices_[k]] = k;
      }
      for (int k = PointTetOffsets_[v]; k < PointTetOffsets_[v + 1]; ++k)
      {
        const int t = PointTets_[k];
        const int* tv = &Tets_[4 * static_cast<size_t>(t)];
        const int a = tv[0] == v ? 0 : tv[1] == v ? 1 : tv[2] == v ? 2 : 3;
        int* positions = &TetNonZeros_[16 * static_cast<size_t>(t) + 4 * a];
        for (int b = 0; b < 4; ++b)
        {
          positions[b] = rank[tv[b]];
        }
      }
    }
  }
}

void TetMesh::BuildScatterSchedule()
{
  const int numPoints = GetNumberOfPoints();
  const int numTets = GetNumberOfTets();
  const int chunkSize = ScatterChunkSize(numTets);
  const int numChunks = (numTets + chunkSize - 1) / chunkSize;
  auto chunkBegin = [&](int k) { return k * chunkSize; };
  auto chunkEnd = [&](int k) { return std::min(numTets, (k + 1) * chunkSize); };

  // Greedy colouring of the chunks of `order`: two chunks sharing a vertex
  // get different colours. Colours are handed out in rounds of 64 (one bit
  // per colour in a per-vertex mask); a chunk finding all 64 colours of a
  // round taken waits for the next round. Returns the number of colours.
  std::vector<int> colour(numChunks, -1);
  auto colourChunks = [&](const std::vector<int>& order)
  {
    std::vector<int> pending(numChunks);
    std::iota(pending.begin(), pending.end(), 0);
    std::vector<std::uint64_t> used;
    int round = 0;
    while (!pending.empty())
    {
      used.assign(numPoints, 0);
      std::vector<int> deferred;
      for (int k : pending)
      {
        std::uint64_t forbidden = 0;
        for (int s = chunkBegin(k); s < chunkEnd(k); ++s)
        {
          const int* tv = GetTet(order[s]);
          forbidden |= used[tv[0]] | used[tv[1]] | used[tv[2]] | used[tv[3]];
        }
        if (forbidden == ~std::uint64_t(0))
        {
          deferred.push_back(k);
          continue;
        }
        int c = 0;
        while (forbidden & (std::uint64_t(1) << c))
        {
          ++c;
        }
        colour[k] = 64 * round + c;
        const std::uint64_t bit = std::uint64_t(1) << c;
        for (int s = chunkBegin(k); s < chunkEnd(k); ++s)
        {
          const int* tv = GetTet(order[s]);
          used[tv[0]] |= bit;
          used[tv[1]] |= bit;
          used[tv[2]] |= bit;
          used[tv[3]] |= bit;
        }
      }
      pending.swap(deferred);
      ++round;
    }
    return numChunks == 0 ? 0 : *std::max_element(colour.begin(), colour.end()) + 1;
  };

  // The tets in their own order: the per-tet arrays the scatter reads
  // (entry positions, geometry, material) are indexed by tet id, so that
  // order streams through them. A mesh from vtkTetrahedralizeSurface is in
  // Morton order, and a cut keeps that order; re-sorting a cut mesh along
  // its own Morton curve (its bounding box changed) made every per-tet read
  // a cache miss (2.4x slower assembly at 540k tets).
  std::vector<int> order(numTets);
  std::iota(order.begin(), order.end(), 0);
  int numColours = colourChunks(order);
  if (numColours > 64)
  {
    // The tet order is not spatially coherent (its chunks are scattered in
    // space and conflict with each other): chunks of the Morton curve of
    // the tet centroids colour with few colours.
    const MortonEncoder encode(Points_);
    order = SortByCode(CentroidCodes(encode, Points_, Tets_));
    numColours = colourChunks(order);
  }

  // Group the chunks by colour (stable: chunks of one colour in order).
  Schedule_.ColourOffsets.assign(static_cast<size_t>(numColours) + 1, 0);
  for (int k = 0; k < numChunks; ++k)
  {
    ++Schedule_.ColourOffsets[colour[k] + 1];
  }
  for (int c = 0; c < numColours; ++c)
  {
    Schedule_.ColourOffsets[c + 1] += Schedule_.ColourOffsets[c];
  }
  std::vector<int> chunksByColour(numChunks);
  {
    std::vector<int> cursor(Schedule_.ColourOffsets.begin(), Schedule_.ColourOffsets.end() - 1);
    for (int k = 0; k < numChunks; ++k)
    {
      chunksByColour[cursor[colour[k]]++] = k;
    }
  }
  Schedule_.ChunkOffsets.assign(static_cast<size_t>(numChunks) + 1, 0);
  Schedule_.Tets.resize(numTets);
  for (int m = 0; m < numChunks; ++m)
  {
    const int k = chunksByColour[m];
    const int begin = Schedule_.ChunkOffsets[m];
    std::copy(
      order.begin() + chunkBegin(k), order.begin() + chunkEnd(k), Schedule_.Tets.begin() + begin);
    Schedule_.ChunkOffsets[m + 1] = begin + (chunkEnd(k) - chunkBegin(k));
  }
}

void TetMesh::ComputeMeasures()
{
  const int numPoints = GetNumberOfPoints();

  // V_i = sum of the volumes of the tets around i (TransCut Sec. 3.1: |Upsilon| ~ V_i/4).
  VertexVolume_.assign(numPoints, 0.0);
#pragma omp parallel for schedule(static)
  for (int i = 0; i < numPoints; ++i)
  {
    double sum = 0.0;
    for (int k = PointTetOffsets_[i]; k < PointTetOffsets_[i + 1]; ++k)
    {
      sum += TetVolumes_[PointTets_[k]];
    }
    VertexVolume_[i] = sum;
  }

  // S_i = sum of the areas of the boundary triangles around i (TransCut eq. 11).
  const int numTriangles = GetNumberOfBoundaryTriangles();
  BoundaryTriangleAreas_.resize(numTriangles);
  BoundaryArea_.assign(numPoints, 0.0);
  PointNormals_.assign(3 * static_cast<size_t>(numPoints), 0.0);
  for (int f = 0; f < numTriangles; ++f)
  {
    const int* tri = &BoundaryTriangles_[3 * static_cast<size_t>(f)];
    double e1[3], e2[3], n[3];
    Sub(GetPoint(tri[1]), GetPoint(tri[0]), e1);
    Sub(GetPoint(tri[2]), GetPoint(tri[0]), e2);
    Cross(e1, e2, n);
    // Area vector: unit normal times area.
    n[0] *= 0.5;
    n[1] *= 0.5;
    n[2] *= 0.5;
    const double area = std::sqrt(Dot(n, n));
    BoundaryTriangleAreas_[f] = area;
    for (int m = 0; m < 3; ++m)
    {
      const int i = tri[m];
      BoundaryArea_[i] += area;
      PointNormals_[3 * static_cast<size_t>(i) + 0] += n[0];
      PointNormals_[3 * static_cast<size_t>(i) + 1] += n[1];
      PointNormals_[3 * static_cast<size_t>(i) + 2] += n[2];
    }
  }
  BoundaryPoints_.clear();
  // Boundary point index of each point (-1 inside), for the incidence below.
  std::vector<int> boundaryIndex(numPoints, -1);
  for (int i = 0; i < numPoints; ++i)
  {
    if (BoundaryArea_[i] > 0.0)
    {
      boundaryIndex[i] = static_cast<int>(BoundaryPoints_.size());
      BoundaryPoints_.push_back(i);
      double* n = &PointNormals_[3 * static_cast<size_t>(i)];
      const double length = std::sqrt(Dot(n, n));
      if (length > 0.0)
      {
        n[0] /= length;
        n[1] /= length;
        n[2] /= length;
      }
    }
  }

  // Boundary point-triangle incidence (counting sort by point: each point's
  // triangles in increasing id order). A triangle of zero area still lists
  // its points that have another triangle.
  const size_t numBoundary = BoundaryPoints_.size();
  BoundaryPointTriangleOffsets_.assign(numBoundary + 1, 0);
  for (int id : BoundaryTriangles_)
  {
    if (boundaryIndex[id] >= 0)
    {
      ++BoundaryPointTriangleOffsets_[boundaryIndex[id] + 1];
    }
  }
  std::partial_sum(BoundaryPointTriangleOffsets_.begin(), BoundaryPointTriangleOffsets_.end(),
    BoundaryPointTriangleOffsets_.begin());
  BoundaryPointTriangles_.resize(BoundaryPointTriangleOffsets_.back());
  std::vector<int> cursor(BoundaryPointTriangleOffsets_.begin(), BoundaryPointTriangleOffsets_.end() - 1);
  for (int f = 0; f < numTriangles; ++f)
  {
    for (int m = 0; m < 3; ++m)
    {
      const int k = boundaryIndex[BoundaryTriangles_[3 * static_cast<size_t>(f) + m]];
      if (k >= 0)
      {
        BoundaryPointTriangles_[cursor[k]++] = f;
      }
    }
  }
}

void TetMesh::ComputeSpatialOrder(const std::vector<double>& points,
  const std::vector<int>& tets,
  std::vector<int>& pointOrder,
  std::vector<int>& tetOrder)
{
  CheckPointsFinite(points);
  CheckTetIds(tets, static_cast<int>(points.size() / 3));
  const MortonEncoder encode(points);
  const int numPoints = static_cast<int>(points.size() / 3);
  std::vector<std::uint64_t> codes(numPoints);
#pragma omp parallel for schedule(static)
  for (int i = 0; i < numPoints; ++i)
  {
    codes[i] = encode(&points[3 * static_cast<size_t>(i)]);
  }
  pointOrder = SortByCode(codes);
  tetOrder = SortByCode(CentroidCodes(encode, points, tets));
}

namespace
{
template <typename T>
std::size_t BytesOf(const std::vector<T>& v)
{
  return v.capacity() * sizeof(T);
}
} // namespace

std::size_t TetMesh::GetGeometryMemoryBytes() const
{
  return BytesOf(Points_) + BytesOf(Tets_);
}

std::size_t TetMesh::GetTopologyMemoryBytes() const
{
  return BytesOf(TetVolumes_) + BytesOf(BoundaryTriangles_) + BytesOf(BoundaryTriangleTets_) +
    BytesOf(BoundaryTriangleAreas_) + BytesOf(BoundaryPoints_) +
    BytesOf(BoundaryPointTriangleOffsets_) + BytesOf(BoundaryPointTriangles_) +
    BytesOf(VertexVolume_) + BytesOf(BoundaryArea_) + BytesOf(PointNormals_) +
    BytesOf(RowOffsets_) + BytesOf(ColumnIndices_) + BytesOf(DiagonalPositions_) +
    BytesOf(PointTetOffsets_) + BytesOf(PointTets_) + BytesOf(TetNonZeros_) +
    BytesOf(Schedule_.Tets) + BytesOf(Schedule_.ChunkOffsets) + BytesOf(Schedule_.ColourOffsets);
}

} // namespace translucency
