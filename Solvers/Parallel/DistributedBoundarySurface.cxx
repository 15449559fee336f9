#include "DistributedBoundarySurface.h"

#include "Error.h"
#include "Timer.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

namespace translucency
{

namespace
{

/// A physical triangle as gathered: global rows and its tet's eta.
struct TriangleRecord
{
  int Rows[3];
  int Padding;
  double Eta;
};

/// A physical boundary point as gathered.
struct PointRecord
{
  int Row;
  int Padding;
  double X[3];
};

/// Every rank's `mine`, concatenated in rank order, on every rank.
template <typename T>
std::vector<T> AllGather(MPI_Comm comm, const std::vector<T>& mine, long long& bytes)
{
  int size = 1;
  MPI_Comm_size(comm, &size);
  const long long myBytes = static_cast<long long>(mine.size() * sizeof(T));
  std::vector<long long> all(static_cast<std::size_t>(size));
  MPI_Allgather(&myBytes, 1, MPI_LONG_LONG, all.data(), 1, MPI_LONG_LONG, comm);
  long long total = 0;
  for (long long b : all)
    total += b;
  if (total > INT_MAX)
  {
    throw Error("distributed surface irradiance: the boundary surface takes " +
      std::to_string(total) + " bytes, above MPI's 2 GB per gather");
  }
  std::vector<int> counts(static_cast<std::size_t>(size)), displs(static_cast<std::size_t>(size), 0);
  for (int r = 0; r < size; ++r)
  {
    counts[r] = static_cast<int>(all[r]);
    if (r > 0)
      displs[r] = displs[r - 1] + counts[r - 1];
  }
  std::vector<T> result(static_cast<std::size_t>(total) / sizeof(T));
  MPI_Allgatherv(mine.data(), static_cast<int>(myBytes), MPI_BYTE, result.data(), counts.data(),
    displs.data(), MPI_BYTE, comm);
  bytes += total;
  return result;
}

/// The global rows of the triangles (`rows`, 3 each) and, per triangle, how
/// many ranks hold it (CountSharedTriangles). Every rank throws the same
/// error for a triangle held by more than two ranks or an invalid eta under
/// a physical triangle. `gathered`: how to select the gathered path instead.
std::vector<int> ClassifyTriangles(MPI_Comm comm, const DistributedNumbering& numbering,
  const std::vector<int>& triangles, const std::vector<double>& triangleEta,
  const std::vector<int>& triangleTets, const char* gathered, std::vector<int>& rows)
{
  const std::size_t numTriangles = triangles.size() / 3;
  rows.resize(3 * numTriangles);
  for (std::size_t k = 0; k < rows.size(); ++k)
    rows[k] = numbering.GetRow(triangles[k]);
  std::vector<int> seen = CountSharedTriangles(comm, rows);
  std::string error;
  for (std::size_t f = 0; f < numTriangles && error.empty(); ++f)
  {
    if (seen[f] > 2)
    {
      std::ostringstream msg;
      msg << "the boundary face of tet " << triangleTets[f] << " is held by " << seen[f]
          << " pieces: overlapping pieces without ghost marks (use the gathered path, "
          << gathered << ")";
      error = msg.str();
    }
    if (seen[f] == 1 && (!(triangleEta[f] > 0.0) || !std::isfinite(triangleEta[f])))
    {
      std::ostringstream msg;
      msg << "RefractiveIndex of tet " << triangleTets[f] << " (under a boundary face) is "
          << triangleEta[f] << ": must be finite and > 0";
      error = msg.str();
    }
  }
  AgreeOnError(comm, error);
  return seen;
}

/// GatherBoundarySurface: the diagonal of the bounding box of every rank's
/// points (the serial one: every point), 0 without points (collective).
double GlobalDiagonal(MPI_Comm comm, const std::vector<double>& points, std::size_t numPoints)
{
  double box[6];
  for (int k = 0; k < 3; ++k)
  {
    box[k] = std::numeric_limits<double>::infinity();      // min
    box[3 + k] = std::numeric_limits<double>::infinity();  // -max
  }
  for (std::size_t i = 0; i < numPoints; ++i)
  {
    for (int k = 0; k < 3; ++k)
    {
      box[k] = std::min(box[k], points[3 * i + k]);
      box[3 + k] = std::min(box[3 + k], -points[3 * i + k]);
    }
  }
  MPI_Allreduce(MPI_IN_PLACE, box, 6, MPI_DOUBLE, MPI_MIN, comm);
  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k)
  {
    lo[k] = box[k];
    hi[k] = -box[3 + k];
  }
  return std::isfinite(lo[0])
    ? std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
        (hi[2] - lo[2]) * (hi[2] - lo[2]))
    : 0.0;
}

} // namespace

double TriangleHalfNormal(const double* p0, const double* p1, const double* p2, double n[3])
{
  const double e1[3] = { p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2] };
  const double e2[3] = { p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2] };
  n[0] = 0.5 * (e1[1] * e2[2] - e1[2] * e2[1]);
  n[1] = 0.5 * (e1[2] * e2[0] - e1[0] * e2[2]);
  n[2] = 0.5 * (e1[0] * e2[1] - e1[1] * e2[0]);
  return std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

void GatherBoundarySurface(MPI_Comm comm, const std::vector<double>& points,
  const std::vector<PointKey>& keys, const std::vector<char>& used,
  const std::vector<int>& triangles, const std::vector<double>& triangleEta,
  const std::vector<int>& triangleTets, BoundarySurface& surface,
  std::vector<int>& surfacePoint, std::vector<double>& rotations,
  BoundarySurfaceReport& report, const std::vector<double>* triangleData,
  int valuesPerTriangle, std::vector<double>* gatheredData, std::vector<int>* gatheredTriangles)
{
  const Timer timer;
  report = BoundarySurfaceReport();
  const std::size_t numPoints = keys.size();
  const std::size_t numTriangles = triangles.size() / 3;

  // The bounding box of every rank's points (the serial one: every point).
  surface.Diagonal = GlobalDiagonal(comm, points, numPoints);

  // Global rows, and the physical triangles: those no other rank has.
  DistributedNumbering numbering;
  numbering.Build(comm, keys, used);
  std::vector<int> rows;
  const std::vector<int> seen = ClassifyTriangles(comm, numbering, triangles, triangleEta,
    triangleTets, "TRANSLUCENCY_GATHERED_IRRADIANCE=1", rows);
  std::vector<TriangleRecord> myTriangles;
  std::vector<double> myData;
  const std::size_t perTriangle =
    triangleData && gatheredData ? static_cast<std::size_t>(std::max(0, valuesPerTriangle)) : 0;
  std::vector<char> onSurface(numPoints, 0);
  if (gatheredTriangles)
    gatheredTriangles->clear();
  for (std::size_t f = 0; f < numTriangles; ++f)
  {
    if (seen[f] != 1)
      continue;
    if (gatheredTriangles)
      gatheredTriangles->push_back(static_cast<int>(f));
    for (std::size_t k = 0; k < perTriangle; ++k)
      myData.push_back((*triangleData)[perTriangle * f + k]);
    TriangleRecord record;
    record.Padding = 0;
    record.Eta = triangleEta[f];
    for (int m = 0; m < 3; ++m)
    {
      record.Rows[m] = rows[3 * f + m];
      onSurface[static_cast<std::size_t>(triangles[3 * f + m])] = 1;
    }
    myTriangles.push_back(record);
  }

  std::vector<PointRecord> myPoints;
  for (std::size_t i = 0; i < numPoints; ++i)
  {
    if (!onSurface[i])
      continue;
    PointRecord record;
    record.Row = numbering.GetRow(static_cast<int>(i));
    record.Padding = 0;
    std::memcpy(record.X, &points[3 * i], sizeof record.X);
    myPoints.push_back(record);
  }
  std::sort(myPoints.begin(), myPoints.end(),
    [](const PointRecord& a, const PointRecord& b) { return a.Row < b.Row; });
  myPoints.erase(std::unique(myPoints.begin(), myPoints.end(),
                   [](const PointRecord& a, const PointRecord& b) { return a.Row == b.Row; }),
    myPoints.end());

  std::vector<PointRecord> allPoints = AllGather(comm, myPoints, report.GatheredBytes);
  myPoints = {};
  std::sort(allPoints.begin(), allPoints.end(),
    [](const PointRecord& a, const PointRecord& b) { return a.Row < b.Row; });
  allPoints.erase(std::unique(allPoints.begin(), allPoints.end(),
                    [](const PointRecord& a, const PointRecord& b) { return a.Row == b.Row; }),
    allPoints.end());
  std::vector<int> surfaceRows(allPoints.size());
  surface.Points.resize(3 * allPoints.size());
  rotations.resize(allPoints.size());
  for (std::size_t p = 0; p < allPoints.size(); ++p)
  {
    surfaceRows[p] = allPoints[p].Row;
    std::memcpy(&surface.Points[3 * p], allPoints[p].X, sizeof allPoints[p].X);
  }
  // The uniform light's rotation is a hash of the point's coordinates, as
  // in the serial code: the same on every rank and for any partition.
  for (std::size_t p = 0; p < allPoints.size(); ++p)
    rotations[p] = UniformSampleRotation(allPoints[p].X);
  allPoints = {};
  auto indexOf = [&surfaceRows](int row) {
    const auto it = std::lower_bound(surfaceRows.begin(), surfaceRows.end(), row);
    return it != surfaceRows.end() && *it == row ? static_cast<int>(it - surfaceRows.begin())
                                                 : -1;
  };

  const std::vector<TriangleRecord> allTriangles =
    AllGather(comm, myTriangles, report.GatheredBytes);
  if (perTriangle > 0)
    *gatheredData = AllGather(comm, myData, report.GatheredBytes); // the same rank order
  surface.Triangles.resize(3 * allTriangles.size());
  surface.TriangleEta.resize(allTriangles.size());
  for (std::size_t f = 0; f < allTriangles.size(); ++f)
  {
    for (int m = 0; m < 3; ++m)
      surface.Triangles[3 * f + m] = indexOf(allTriangles[f].Rows[m]);
    surface.TriangleEta[f] = allTriangles[f].Eta;
  }
  surfacePoint.assign(numPoints, -1);
  for (std::size_t i = 0; i < numPoints; ++i)
  {
    const int row = numbering.GetRow(static_cast<int>(i));
    if (row >= 0)
      surfacePoint[i] = indexOf(row);
  }
  report.Triangles = static_cast<long long>(surface.GetNumberOfTriangles());
  report.Points = static_cast<long long>(surface.GetNumberOfPoints());
  report.Milliseconds = timer.GetMilliseconds();
}

void FindPieceBoundary(MPI_Comm comm, const std::vector<double>& points,
  const std::vector<PointKey>& keys, const std::vector<char>& used,
  const std::vector<int>& triangles, const std::vector<double>& triangleEta,
  const std::vector<int>& triangleTets, const char* gathered, PieceBoundary& boundary)
{
  const std::size_t numPoints = keys.size();
  const std::size_t numTriangles = triangles.size() / 3;
  DistributedNumbering numbering;
  numbering.Build(comm, keys, used);
  std::vector<int> rows;
  const std::vector<int> seen =
    ClassifyTriangles(comm, numbering, triangles, triangleEta, triangleTets, gathered, rows);
  // Per local point: S_i, the area vector and area x eta of this rank's
  // physical triangles around it (TetMesh::ComputeMeasures' expressions),
  // summed over the ranks at the owners and handed back.
  std::vector<double> sums(5 * numPoints, 0.0);
  boundary.Physical.assign(numTriangles, 0);
  long long mine = 0;
  for (std::size_t f = 0; f < numTriangles; ++f)
  {
    if (seen[f] != 1)
      continue;
    boundary.Physical[f] = 1;
    ++mine;
    double n[3];
    const double area = TriangleHalfNormal(&points[3 * static_cast<std::size_t>(triangles[3 * f])],
      &points[3 * static_cast<std::size_t>(triangles[3 * f + 1])],
      &points[3 * static_cast<std::size_t>(triangles[3 * f + 2])], n);
    for (int m = 0; m < 3; ++m)
    {
      double* to = &sums[5 * static_cast<std::size_t>(triangles[3 * f + m])];
      to[0] += area;
      to[1] += n[0];
      to[2] += n[1];
      to[3] += n[2];
      to[4] += area * triangleEta[f];
    }
  }
  MPI_Allreduce(&mine, &boundary.Triangles, 1, MPI_LONG_LONG, MPI_SUM, comm);
  const std::vector<double> global =
    numbering.FetchFromOwners(comm, numbering.SumToOwners(comm, sums, 5), 5);
  boundary.PointArea.assign(numPoints, 0.0);
  boundary.PointNormal.assign(3 * numPoints, 0.0);
  boundary.PointEta.assign(numPoints, 0.0);
  boundary.Owned.assign(numPoints, 0);
  // A row held twice by this rank (a piece read as several parts) is owned
  // by its first local point only.
  std::vector<char> rowTaken(static_cast<std::size_t>(numbering.GetNumberOfOwnedRows()), 0);
  for (std::size_t i = 0; i < numPoints; ++i)
  {
    const double* g = &global[5 * i];
    if (!(g[0] > 0.0))
      continue;
    boundary.PointArea[i] = g[0];
    const double length = std::sqrt(g[1] * g[1] + g[2] * g[2] + g[3] * g[3]);
    for (int k = 0; k < 3; ++k)
      boundary.PointNormal[3 * i + k] = length > 0.0 ? g[1 + k] / length : g[1 + k];
    boundary.PointEta[i] = g[4] / g[0];
    if (numbering.IsOwned(static_cast<int>(i)))
    {
      char& taken = rowTaken[static_cast<std::size_t>(
        numbering.GetRow(static_cast<int>(i)) - numbering.GetRowBegin())];
      boundary.Owned[i] = taken ? 0 : 1;
      taken = 1;
    }
  }
}

} // namespace translucency
