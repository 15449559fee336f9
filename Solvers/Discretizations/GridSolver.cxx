#include "GridSolver.h"
#include "ResourceLimits.h"

#include "Error.h"
#include "Fresnel.h"
#include "Relaxation.h"
#include "Strings.h"
#include "TetMesh.h"
#include "TriangleGeometry.h"
#include "Timer.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <omp.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <limits>
#include <sstream>

namespace translucency
{

namespace
{

const char* const ChannelNames[NumberOfChannels] = { "R", "G", "B" };
/// Direction k of a link: axis Axis[k], sign Sign[k] (0 +x, 1 -x, 2 +y, ...).
constexpr int Axis[6] = { 0, 0, 1, 1, 2, 2 };
constexpr int Sign[6] = { 1, -1, 1, -1, 1, -1 };
/// Shortest link to a boundary node, as a fraction of h: shorter links
/// (a node almost on the surface) are lengthened to this, which moves the
/// surface point by less than 0.1 h (the scheme is first order anyway) and
/// keeps the coupling of the node and its boundary node from dominating
/// the row (which would stall the relaxation and worsen conditioning).
constexpr double MinDistanceFraction = 0.1;
/// Unknowns per thread below which the default thread count is reduced:
/// on small grids fork/join and barriers cost more than the work.
constexpr int UnknownsPerThread = 50000;
/// Depths (in h) along the inward normal at which the normal derivative of a
/// boundary node on a slanted face is probed, in order of preference.
constexpr double ProbeDepths[] = { 1.0, 1.5, 2.0, 2.5, 3.0, 0.75, 0.5 };
/// Estimated bytes per unknown: CSR row of 7 entries (4 + 3 x 8 bytes each),
/// offsets, node data, material and sources (3 channels), right-hand sides
/// and solutions, and BiCGSTAB's 10 work vectors.
constexpr double BytesPerUnknown = 400.0;
/// Multi-level: a coarser level is built while the finer one has more
/// unknowns than this, and kept if it has at least MinCoarseUnknowns.
constexpr int CoarsenAbove = 4096;
constexpr int MinCoarseUnknowns = 512;
constexpr int MaxCoarseLevels = 6;

/**
 * While alive, lets OpenMP give parallel regions fewer threads than asked
 * when the machine is busy (omp_set_dynamic: libgomp subtracts the load
 * average from the processors). On an oversubscribed machine threads that
 * wait at barriers for a descheduled partner cost far more than the work.
 * The results do not depend on the number of threads, so this changes only
 * the speed. Restores the previous setting.
 */
class DynamicThreads
{
public:
  explicit DynamicThreads(bool on)
    : Previous_(omp_get_dynamic())
  {
    omp_set_dynamic(on ? 1 : 0);
  }
  ~DynamicThreads() { omp_set_dynamic(Previous_); }
  DynamicThreads(const DynamicThreads&) = delete;
  DynamicThreads& operator=(const DynamicThreads&) = delete;

private:
  int Previous_;
};

/// Bounding box of the points used by tets: min x, y, z, max x, y, z.
void TetBounds(const TetMesh& mesh, double bounds[6])
{
  for (int d = 0; d < 3; ++d)
  {
    bounds[d] = std::numeric_limits<double>::infinity();
    bounds[d + 3] = -std::numeric_limits<double>::infinity();
  }
  for (int id : mesh.GetTets())
  {
    const double* p = mesh.GetPoint(id);
    for (int d = 0; d < 3; ++d)
    {
      bounds[d] = std::min(bounds[d], p[d]);
      bounds[d + 3] = std::max(bounds[d + 3], p[d]);
    }
  }
}

/// Nodes per axis (as doubles: they may not fit an int) of spacing h.
void GridCounts(const double bounds[6], double h, double counts[3])
{
  for (int d = 0; d < 3; ++d)
  {
    // The slack keeps an extent of exactly n h at n nodes despite rounding.
    counts[d] = std::max(1.0, std::ceil((bounds[d + 3] - bounds[d]) / h - 1e-9));
  }
}

/// Barycentric weights of p (on or near the plane of a, b, c), clamped to
/// the triangle and normalised.
void TriangleWeights(const Eigen::Vector3d& p,
  const Eigen::Vector3d& a,
  const Eigen::Vector3d& b,
  const Eigen::Vector3d& c,
  double w[3])
{
  const Eigen::Vector3d v0 = b - a, v1 = c - a, v2 = p - a;
  const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1);
  const double d20 = v2.dot(v0), d21 = v2.dot(v1);
  const double denom = d00 * d11 - d01 * d01;
  double u = 1.0 / 3, v = 1.0 / 3;
  if (denom > 0.0)
  {
    u = (d11 * d20 - d01 * d21) / denom;
    v = (d00 * d21 - d01 * d20) / denom;
  }
  w[1] = std::clamp(u, 0.0, 1.0);
  w[2] = std::clamp(v, 0.0, 1.0);
  w[0] = std::max(0.0, 1.0 - w[1] - w[2]);
  const double sum = w[0] + w[1] + w[2];
  for (int k = 0; k < 3; ++k)
  {
    w[k] /= sum;
  }
}

/// Fluence of a level's solution at x (see GridSolver::EvaluateGrid).
void EvaluateLevel(const GridLevel& level, const double x[3], double out[NumberOfChannels])
{
  const double h = level.Spacing;
  const int* dims = level.Dims;
  const int numInterior = level.NumberOfInterior();
  int i0[3];
  double t[3];
  for (int d = 0; d < 3; ++d)
  {
    const double f = std::clamp((x[d] - level.Origin[d]) / h, -4.0, dims[d] + 4.0);
    i0[d] = static_cast<int>(std::floor(f));
    t[d] = f - i0[d];
  }
  auto unknownAt = [&](int i, int j, int k)
  {
    if (i < 0 || j < 0 || k < 0 || i >= dims[0] || j >= dims[1] || k >= dims[2])
    {
      return -1;
    }
    return level
      .NodeUnknown[i + static_cast<size_t>(dims[0]) * (j + static_cast<size_t>(dims[1]) * k)];
  };
  // Trilinear when the 8 corners are interior.
  int corner[8];
  bool all = true;
  for (int c = 0; c < 8 && all; ++c)
  {
    corner[c] = unknownAt(i0[0] + (c & 1), i0[1] + ((c >> 1) & 1), i0[2] + ((c >> 2) & 1));
    all = corner[c] >= 0;
  }
  if (all)
  {
    for (int ch = 0; ch < NumberOfChannels; ++ch)
    {
      double v = 0.0;
      for (int c = 0; c < 8; ++c)
      {
        const double w = ((c & 1) ? t[0] : 1.0 - t[0]) * (((c >> 1) & 1) ? t[1] : 1.0 - t[1]) *
          (((c >> 2) & 1) ? t[2] : 1.0 - t[2]);
        v += w * level.Solution[ch][corner[c]];
      }
      out[ch] = v;
    }
    return;
  }
  // Otherwise a linear function fitted by weighted least squares to the
  // interior nodes of growing blocks of nodes around x and their boundary
  // nodes (linear-exact, so first-order errors of the nodes are not made
  // worse by the offsets); if the fit is not determined, the weighted mean.
  const int maxDim = std::max({ dims[0], dims[1], dims[2] });
  std::vector<std::array<double, 3 + NumberOfChannels>> samples; // dx / h, values
  for (int r = 1;; ++r)
  {
    int lo[3], hi[3];
    bool whole = true;
    for (int d = 0; d < 3; ++d)
    {
      lo[d] = std::max(0, i0[d] - r + 1);
      hi[d] = std::min(dims[d] - 1, i0[d] + r);
      whole = whole && lo[d] == 0 && hi[d] == dims[d] - 1;
    }
    samples.clear();
    auto add = [&](int u)
    {
      double p[3];
      level.Position(u, p);
      samples.push_back({ (p[0] - x[0]) / h,
        (p[1] - x[1]) / h,
        (p[2] - x[2]) / h,
        level.Solution[0][u],
        level.Solution[1][u],
        level.Solution[2][u] });
    };
    for (int k = lo[2]; k <= hi[2]; ++k)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int i = lo[0]; i <= hi[0]; ++i)
        {
          const int u = unknownAt(i, j, k);
          if (u < 0)
          {
            continue;
          }
          add(u);
          for (int b = level.BoundaryOffsets[u]; b < level.BoundaryOffsets[u + 1]; ++b)
          {
            add(numInterior + b);
          }
        }
    const bool last = whole || r >= 3 || r > 2 * maxDim + 8;
    if (samples.size() >= 4)
    {
      // Weights 1 / (r^2 + (0.1 h)^2); normal equations in units of h.
      Eigen::Matrix4d a = Eigen::Matrix4d::Zero();
      Eigen::Matrix<double, 4, NumberOfChannels> rhs =
        Eigen::Matrix<double, 4, NumberOfChannels>::Zero();
      for (const auto& sample : samples)
      {
        const Eigen::Vector4d basis(1.0, sample[0], sample[1], sample[2]);
        const double w = 1.0 / (basis.tail<3>().squaredNorm() + 0.01);
        a.noalias() += w * basis * basis.transpose();
        for (int ch = 0; ch < NumberOfChannels; ++ch)
        {
          rhs.col(ch) += w * sample[3 + ch] * basis;
        }
      }
      const Eigen::LDLT<Eigen::Matrix4d> ldlt(a);
      const Eigen::Vector4d pivots = ldlt.vectorD().cwiseAbs();
      if (ldlt.info() == Eigen::Success && pivots.minCoeff() > 1e-8 * pivots.maxCoeff())
      {
        const Eigen::Matrix<double, 4, NumberOfChannels> c = ldlt.solve(rhs);
        for (int ch = 0; ch < NumberOfChannels; ++ch)
        {
          out[ch] = std::max(0.0, c(0, ch)); // fluence is not negative
        }
        return;
      }
    }
    if (!samples.empty() && last)
    {
      double sumW = 0.0, sum[NumberOfChannels] = { 0.0, 0.0, 0.0 };
      for (const auto& sample : samples)
      {
        const double w =
          1.0 / (sample[0] * sample[0] + sample[1] * sample[1] + sample[2] * sample[2] + 1e-12);
        sumW += w;
        for (int ch = 0; ch < NumberOfChannels; ++ch)
        {
          sum[ch] += w * sample[3 + ch];
        }
      }
      for (int ch = 0; ch < NumberOfChannels; ++ch)
      {
        out[ch] = sum[ch] / sumW;
      }
      return;
    }
    if (whole || r > 2 * maxDim + 8)
    {
      for (int ch = 0; ch < NumberOfChannels; ++ch)
      {
        out[ch] = 0.0; // no interior node at all (PrepareGrid forbids it)
      }
      return;
    }
  }
}

/**
 * The interior sources' share of each interior node of a level (W per
 * channel, added to `power`, 3 per interior node): trilinear weights over
 * the 8 corners of the grid cell containing the source, renormalised over
 * the corners that are interior nodes; if none is, all the power to the
 * nearest interior node of the 4^3, then 6^3 block around it. Throws
 * translucency::Error naming the source if that finds none (a part of the
 * object thinner than the spacing).
 */
void DistributeSources(
  const GridLevel& level, const std::vector<PlacedSource>& sources, std::vector<double>& power)
{
  const double h = level.Spacing;
  auto unknownAt = [&level](int i, int j, int k)
  {
    if (i < 0 || j < 0 || k < 0 || i >= level.Dims[0] || j >= level.Dims[1] || k >= level.Dims[2])
    {
      return -1;
    }
    return level.NodeUnknown[i +
      static_cast<size_t>(level.Dims[0]) * (j + static_cast<size_t>(level.Dims[1]) * k)];
  };
  for (const PlacedSource& placed : sources)
  {
    const double* x = placed.Source.Position.data();
    int base[3];
    double t[3];
    for (int d = 0; d < 3; ++d)
    {
      const double u = (x[d] - level.Origin[d]) / h;
      base[d] = static_cast<int>(std::floor(u));
      t[d] = u - base[d];
    }
    int nodes[8];
    double weights[8];
    double total = 0.0;
    for (int corner = 0; corner < 8; ++corner)
    {
      const int b[3] = { corner & 1, (corner >> 1) & 1, (corner >> 2) & 1 };
      nodes[corner] = unknownAt(base[0] + b[0], base[1] + b[1], base[2] + b[2]);
      weights[corner] = 1.0;
      for (int d = 0; d < 3; ++d)
      {
        weights[corner] *= b[d] ? t[d] : 1.0 - t[d];
      }
      if (nodes[corner] < 0)
      {
        weights[corner] = 0.0;
      }
      total += weights[corner];
    }
    if (!(total > 1e-12))
    {
      // No interior corner (or only at weight ~0): the nearest interior node.
      int best = -1;
      double bestDistance = std::numeric_limits<double>::infinity();
      for (int half : { 2, 3 })
      {
        for (int k = base[2] - half + 1; k <= base[2] + half; ++k)
        {
          for (int j = base[1] - half + 1; j <= base[1] + half; ++j)
          {
            for (int i = base[0] - half + 1; i <= base[0] + half; ++i)
            {
              const int u = unknownAt(i, j, k);
              if (u < 0)
              {
                continue;
              }
              const double dx = level.Origin[0] + i * h - x[0];
              const double dy = level.Origin[1] + j * h - x[1];
              const double dz = level.Origin[2] + k * h - x[2];
              const double distance = dx * dx + dy * dy + dz * dz;
              if (distance < bestDistance || (distance == bestDistance && u < best))
              {
                best = u;
                bestDistance = distance;
              }
            }
          }
        }
        if (best >= 0)
        {
          break;
        }
      }
      if (best < 0)
      {
        std::ostringstream os;
        os << "grid: " << (placed.Source.Label.empty() ? "point source" : placed.Source.Label)
           << " at " << FormatPoint(x) << " has no grid node inside the object within 3 grid "
           << "spacings (" << h << " mm): the object is thinner than the grid there; use a "
           << "smaller grid spacing";
        throw Error(os.str());
      }
      std::fill(nodes, nodes + 8, -1);
      std::fill(weights, weights + 8, 0.0);
      nodes[0] = best;
      weights[0] = 1.0;
      total = 1.0;
    }
    for (int corner = 0; corner < 8; ++corner)
    {
      if (nodes[corner] < 0 || weights[corner] == 0.0)
      {
        continue;
      }
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        power[3 * static_cast<size_t>(nodes[corner]) + c] +=
          placed.Source.Power[c] * weights[corner] / total;
      }
    }
  }
}

} // namespace

// ---- GridLevel ----

void GridLevel::Position(int u, double x[3]) const
{
  const int numInterior = NumberOfInterior();
  const int interior = u < numInterior ? u : Boundary[u - numInterior].Interior;
  int ijk[3];
  InteriorIndex(interior, ijk);
  for (int d = 0; d < 3; ++d)
  {
    x[d] = Origin[d] + ijk[d] * Spacing;
  }
  if (u >= numInterior)
  {
    const BoundaryNode& node = Boundary[u - numInterior];
    x[Axis[node.Direction]] += Sign[node.Direction] * node.Distance;
  }
}

void GridLevel::ControlExtents(int u, double extent[3]) const
{
  const int numInterior = NumberOfInterior();
  const int* neighbours = &Neighbours[6 * static_cast<size_t>(u)];
  for (int axis = 0; axis < 3; ++axis)
  {
    double sum = 0.0;
    for (int dir = 2 * axis; dir < 2 * axis + 2; ++dir)
    {
      const int v = neighbours[dir];
      sum += v < numInterior ? Spacing : Boundary[v - numInterior].Distance;
    }
    extent[axis] = 0.5 * sum;
  }
}

std::size_t GridLevel::MemoryBytes() const
{
  std::size_t bytes = NodeUnknown.capacity() * sizeof(int) + InteriorGrid.capacity() * sizeof(int) +
    InteriorTet.capacity() * sizeof(int) + BoundaryOffsets.capacity() * sizeof(int) +
    Boundary.capacity() * sizeof(BoundaryNode) + Neighbours.capacity() * sizeof(int) +
    Slots.capacity() +
    (Colours[0].capacity() + Colours[1].capacity() + Colours[2].capacity()) * sizeof(int) +
    (BoundaryRobin.capacity() + BoundaryScale.capacity()) * sizeof(double) +
    System.RowOffsets.capacity() * sizeof(int) + System.ColumnIndices.capacity() * sizeof(int);
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    bytes += (Mu[c].capacity() + Kappa[c].capacity() + BoundaryKappa[c].capacity() +
               BoundarySource[c].capacity() + System.Values[c].capacity()) *
        sizeof(double) +
      (System.RightHandSide[c].size() + Solution[c].size()) * sizeof(double);
  }
  return bytes;
}

// ---- GridSolver ----

int GridSolver::Threads(long long work) const
{
  if (NumberOfThreads_ > 0)
  {
    return NumberOfThreads_;
  }
  return static_cast<int>(
    std::clamp<long long>(work / UnknownsPerThread, 1, omp_get_max_threads()));
}

void GridSolver::Reset()
{
  Levels_.clear();
  Mesh_ = nullptr;
  GeometryRevision_ = 0;
  RequestedSpacing_ = -1.0;
  HasMultiLevel_ = false;
  HaveSolution_ = false;
  RayFallbacks_ = 0;
  CoarseIterations_.fill(0);
}

double GridSolver::ComputeSpacing(const TetMesh& mesh) const
{
  if (mesh.GetNumberOfTets() == 0)
  {
    std::ostringstream os;
    os << "grid: the mesh has no tetrahedra (" << mesh.GetNumberOfPoints()
       << " points): there is no volume to put a grid in";
    throw Error(os.str());
  }
  const double h = GridSpacing_;
  if (!std::isfinite(h) || h < 0.0)
  {
    std::ostringstream os;
    os << "grid: grid spacing " << h << " mm is invalid: it must be > 0 (or 0 for automatic)";
    throw Error(os.str());
  }
  if (h > 0.0)
  {
    // A spacing larger than the object puts at most one node in it: no
    // Laplacian to speak of (1e300 mm gave NaN with exit 0).
    double bounds[6];
    TetBounds(mesh, bounds);
    const double largest =
      std::max({ bounds[3] - bounds[0], bounds[4] - bounds[1], bounds[5] - bounds[2] });
    if (h > largest)
    {
      std::ostringstream os;
      os << std::setprecision(4) << "grid: grid spacing " << h
         << " mm is larger than the object (its bounding box is " << bounds[3] - bounds[0]
         << " x " << bounds[4] - bounds[1] << " x " << bounds[5] - bounds[2]
         << " mm): the grid cannot resolve it; use a spacing of a fraction of " << largest
         << " mm (or 0 for automatic)";
      throw Error(os.str());
    }
    return h;
  }
  double volume = 0.0;
  for (double v : mesh.GetTetVolumes())
  {
    volume += v;
  }
  return std::cbrt(volume / mesh.GetNumberOfTets());
}

double GridSolver::EstimateMemory(const TetMesh& mesh, double h, double* gridNodes) const
{
  double bounds[6], counts[3];
  TetBounds(mesh, bounds);
  GridCounts(bounds, h, counts);
  const double nodes = counts[0] * counts[1] * counts[2];
  if (gridNodes)
  {
    *gridNodes = nodes;
  }
  double volume = 0.0, area = 0.0;
  for (double v : mesh.GetTetVolumes())
  {
    volume += v;
  }
  for (double a : mesh.GetBoundaryTriangleAreas())
  {
    area += a;
  }
  // Nodes inside ~ volume / h^3; links crossing the surface ~ 1.5 area / h^2
  // (the mean of |n_x| + |n_y| + |n_z| over directions).
  const double interior = std::min(nodes, volume / (h * h * h));
  const double boundary = 1.5 * area / (h * h);
  double bytes = 4.0 * nodes + BytesPerUnknown * (interior + boundary);
  if (MultiLevel_)
  {
    bytes *= 8.0 / 7.0;
  }
  return bytes;
}

double GridSolver::GetSpacing() const
{
  return Levels_.empty() ? 0.0 : Levels_[0].Spacing;
}

std::array<int, 3> GridSolver::GetDimensions() const
{
  if (Levels_.empty())
  {
    return { 0, 0, 0 };
  }
  return { Levels_[0].Dims[0], Levels_[0].Dims[1], Levels_[0].Dims[2] };
}

std::array<double, 3> GridSolver::GetOrigin() const
{
  if (Levels_.empty())
  {
    return { 0.0, 0.0, 0.0 };
  }
  return { Levels_[0].Origin[0], Levels_[0].Origin[1], Levels_[0].Origin[2] };
}

int GridSolver::GetNumberOfInteriorNodes() const
{
  return Levels_.empty() ? 0 : Levels_[0].NumberOfInterior();
}

int GridSolver::GetNumberOfBoundaryNodes() const
{
  return Levels_.empty() ? 0 : Levels_[0].NumberOfBoundary();
}

std::array<double, 3> GridSolver::GetNodePosition(int u) const
{
  if (u < 0 || u >= GetNumberOfUnknowns())
  {
    throw Error("grid: node " + std::to_string(u) + " out of range (" +
      std::to_string(GetNumberOfUnknowns()) + " unknowns)");
  }
  std::array<double, 3> x;
  Levels_[0].Position(u, x.data());
  return x;
}

std::array<int, 3> GridSolver::GetInteriorNodeIndex(int u) const
{
  if (u < 0 || u >= GetNumberOfInteriorNodes())
  {
    throw Error("grid: interior node " + std::to_string(u) + " out of range");
  }
  std::array<int, 3> ijk;
  Levels_[0].InteriorIndex(u, ijk.data());
  return ijk;
}

namespace
{
const GridLevel::BoundaryNode& CheckedBoundary(const std::vector<GridLevel>& levels, int b)
{
  if (levels.empty() || b < 0 || b >= levels[0].NumberOfBoundary())
  {
    throw Error("grid: boundary node " + std::to_string(b) + " out of range");
  }
  return levels[0].Boundary[b];
}
}

int GridSolver::GetBoundaryNodeInterior(int b) const
{
  return CheckedBoundary(Levels_, b).Interior;
}

int GridSolver::GetBoundaryNodeDirection(int b) const
{
  return CheckedBoundary(Levels_, b).Direction;
}

double GridSolver::GetBoundaryNodeDistance(int b) const
{
  return CheckedBoundary(Levels_, b).Distance;
}

int GridSolver::GetBoundaryNodeTriangle(int b) const
{
  return CheckedBoundary(Levels_, b).Triangle;
}

const GridLevel& GridSolver::GetLevel(int l) const
{
  if (l < 0 || l >= static_cast<int>(Levels_.size()))
  {
    throw Error("grid: level " + std::to_string(l) + " out of range (" +
      std::to_string(Levels_.size()) + " levels)");
  }
  return Levels_[l];
}

const DiffusionSystem& GridSolver::GetSystem() const
{
  if (Levels_.empty())
  {
    throw Error("grid: no grid yet (call Solve or PrepareGrid first)");
  }
  return Levels_[0].System;
}

const std::array<Eigen::VectorXd, NumberOfChannels>& GridSolver::GetNodeFluence() const
{
  if (Levels_.empty())
  {
    throw Error("grid: no grid yet (call Solve or PrepareGrid first)");
  }
  return Levels_[0].Solution;
}

std::array<double, NumberOfChannels> GridSolver::EvaluateGrid(const double x[3]) const
{
  if (Levels_.empty() || !HaveSolution_)
  {
    throw Error("grid: no solution yet (call Solve first)");
  }
  std::array<double, NumberOfChannels> out;
  EvaluateLevel(Levels_[0], x, out.data());
  return out;
}

// ---- grid construction ----

void GridSolver::PrepareGrid(const TetMesh& mesh)
{
  const DynamicThreads dynamic(NumberOfThreads_ <= 0);
  const double h = ComputeSpacing(mesh); // throws for an empty mesh or a bad spacing
  const std::uint64_t revision = mesh.GetGeometryRevision();
  const bool sameGeometry = !Levels_.empty() && Mesh_ == &mesh && GeometryRevision_ == revision &&
    RequestedSpacing_ == GridSpacing_;
  if (sameGeometry && (HasMultiLevel_ || !MultiLevel_))
  {
    return;
  }
  if (MemoryLimit_ == 0)
  {
    throw Error("grid: the memory limit is 0 bytes: it must be > 0");
  }
  double nodes = 0.0;
  const double bytes = EstimateMemory(mesh, h, &nodes);
  if (bytes > static_cast<double>(MemoryLimit_) || nodes >= static_cast<double>(INT_MAX) / 8)
  {
    std::ostringstream os;
    os << std::setprecision(3) << "grid: grid spacing " << h << " mm needs about "
       << FormatBytes(bytes) << " for " << nodes << " grid nodes; the limit is "
       << FormatBytes(static_cast<double>(MemoryLimit_));
    if (nodes >= static_cast<double>(INT_MAX) / 8)
    {
      os << " and at most " << INT_MAX / 8 << " grid nodes are supported";
    }
    os << ": use a larger spacing (or " << MemoryLimitOverride() << ")";
    throw Error(os.str());
  }

  if (!sameGeometry)
  {
    Reset();
    Locator_.Build(mesh);
    Caster_.Build(mesh.GetPoints(), mesh.GetBoundaryTriangles());
    Levels_.resize(1);
    GridLevel& fine = Levels_[0];
    double bounds[6], counts[3];
    TetBounds(mesh, bounds);
    GridCounts(bounds, h, counts);
    fine.Spacing = h;
    for (int d = 0; d < 3; ++d)
    {
      fine.Dims[d] = static_cast<int>(counts[d]);
      // Centre the block of nodes in the box.
      fine.Origin[d] = 0.5 * (bounds[d] + bounds[d + 3]) - 0.5 * (counts[d] - 1.0) * h;
    }
    const int fallbacks = BuildLevel(mesh, fine);
    if (fine.NumberOfInterior() == 0)
    {
      std::ostringstream os;
      os << "grid: grid spacing " << h << " mm leaves no grid node inside the mesh ("
         << fine.Dims[0] << " x " << fine.Dims[1] << " x " << fine.Dims[2]
         << " nodes in the box): use a smaller spacing";
      Reset();
      throw Error(os.str());
    }
    RayFallbacks_ = fallbacks;
    Mesh_ = &mesh;
    GeometryRevision_ = revision;
    RequestedSpacing_ = GridSpacing_;
  }
  if (MultiLevel_ && !HasMultiLevel_)
  {
    // Coarser levels: nodes at the centres of 2x2x2 blocks of finer nodes.
    while (static_cast<int>(Levels_.size()) <= MaxCoarseLevels &&
      Levels_.back().NumberOfUnknowns() > CoarsenAbove)
    {
      GridLevel coarse;
      const GridLevel& finer = Levels_.back();
      coarse.Spacing = 2.0 * finer.Spacing;
      for (int d = 0; d < 3; ++d)
      {
        coarse.Dims[d] = (finer.Dims[d] + 1) / 2;
        coarse.Origin[d] = finer.Origin[d] + 0.5 * finer.Spacing;
      }
      BuildLevel(mesh, coarse);
      if (coarse.NumberOfUnknowns() < MinCoarseUnknowns || coarse.NumberOfInterior() == 0)
      {
        break;
      }
      Levels_.push_back(std::move(coarse));
    }
    HasMultiLevel_ = true;
  }
}

namespace
{

/// The unknown of the grid neighbour of node ijk in direction dir, or -1
/// (outside the grid or the mesh).
int NeighbourUnknown(const GridLevel& level, const int ijk[3], int dir)
{
  const int nx = level.Dims[0], ny = level.Dims[1];
  const int* unknown = level.NodeUnknown.data();
  int n[3] = { ijk[0], ijk[1], ijk[2] };
  n[Axis[dir]] += Sign[dir];
  if (n[Axis[dir]] < 0 || n[Axis[dir]] >= level.Dims[Axis[dir]])
  {
    return -1;
  }
  return unknown[n[0] + static_cast<size_t>(nx) * (n[1] + static_cast<size_t>(ny) * n[2])];
}

/// Corner m of boundary triangle f.
Eigen::Vector3d TriangleVertex(const TetMesh& mesh, int f, int m)
{
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  return Eigen::Vector3d(mesh.GetPoint(triangles[3 * f + m]));
}

/// BuildLevel, 1. Locate every grid node (tet id, or -1 outside); 2. number
/// the interior nodes in grid order (NodeUnknown then holds the unknowns).
void LocateNodes(const TetLocator& locator, int threads, GridLevel& level)
{
  const int nx = level.Dims[0];
  const int ny = level.Dims[1];
  const int nz = level.Dims[2];
  const long long numNodes =
    static_cast<long long>(level.Dims[0]) * level.Dims[1] * level.Dims[2];
  const double h = level.Spacing;
  level.NodeUnknown.assign(static_cast<size_t>(numNodes), -1);
  int* nodeTet = level.NodeUnknown.data();
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (int k = 0; k < nz; ++k)
  {
    for (int j = 0; j < ny; ++j)
    {
      for (int i = 0; i < nx; ++i)
      {
        const double x[3] = {
          level.Origin[0] + i * h, level.Origin[1] + j * h, level.Origin[2] + k * h
        };
        nodeTet[i + static_cast<size_t>(nx) * (j + static_cast<size_t>(ny) * k)] =
          locator.Locate(x);
      }
    }
  }
  // 2. Number the interior nodes in grid order.
  long long count = 0;
  for (long long g = 0; g < numNodes; ++g)
  {
    count += nodeTet[g] >= 0;
  }
  level.InteriorGrid.resize(static_cast<size_t>(count));
  level.InteriorTet.resize(static_cast<size_t>(count));
  int next = 0;
  for (long long g = 0; g < numNodes; ++g)
  {
    if (nodeTet[g] >= 0)
    {
      level.InteriorGrid[next] = static_cast<int>(g);
      level.InteriorTet[next] = nodeTet[g];
      nodeTet[g] = next++;
    }
  }
}

/// BuildLevel, 3. Boundary nodes: one per outside link, numbered by interior
/// node, then direction, on the first surface crossing of the link.
/// Returns the number of links that needed a fallback.
int PlaceBoundaryNodes(
  const TetMesh& mesh, const RayCaster& caster, int threads, GridLevel& level)
{
  const double h = level.Spacing;
  const int numInterior = static_cast<int>(level.InteriorGrid.size());
  auto neighbourUnknown = [&level](const int ijk[3], int dir)
  { return NeighbourUnknown(level, ijk, dir); };
  level.BoundaryOffsets.assign(static_cast<size_t>(numInterior) + 1, 0);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int u = 0; u < numInterior; ++u)
  {
    int ijk[3];
    level.InteriorIndex(u, ijk);
    int outside = 0;
    for (int dir = 0; dir < 6; ++dir)
    {
      outside += neighbourUnknown(ijk, dir) < 0;
    }
    level.BoundaryOffsets[u + 1] = outside;
  }
  for (int u = 0; u < numInterior; ++u)
  {
    level.BoundaryOffsets[u + 1] += level.BoundaryOffsets[u];
  }
  const int numBoundary = level.BoundaryOffsets[numInterior];
  level.Boundary.assign(static_cast<size_t>(numBoundary), GridLevel::BoundaryNode());
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  const int numTriangles = mesh.GetNumberOfBoundaryTriangles();
  auto vertex = [&](int f, int m) { return Eigen::Vector3d(mesh.GetPoint(triangles[3 * f + m])); };
  int fallbacks = 0;
#pragma omp parallel for schedule(dynamic, 64) num_threads(threads) reduction(+ : fallbacks)
  for (int u = 0; u < numInterior; ++u)
  {
    int ijk[3];
    level.InteriorIndex(u, ijk);
    const double x[3] = {
      level.Origin[0] + ijk[0] * h, level.Origin[1] + ijk[1] * h, level.Origin[2] + ijk[2] * h
    };
    int b = level.BoundaryOffsets[u];
    for (int dir = 0; dir < 6; ++dir)
    {
      if (neighbourUnknown(ijk, dir) >= 0)
      {
        continue;
      }
      GridLevel::BoundaryNode& node = level.Boundary[b++];
      node.Interior = u;
      node.Direction = dir;
      double e[3] = { 0.0, 0.0, 0.0 };
      e[Axis[dir]] = Sign[dir];
      const double reach = h * (1.0 + 1e-9);
      double t = 0.0, d = 0.0;
      int triangle = -1;
      Eigen::Vector3d hit(x[0], x[1], x[2]);
      if (caster.FirstHit(x, e, reach, t, triangle))
      {
        // The first surface crossing on the link from the node outwards.
        d = t;
        hit = Eigen::Vector3d(x[0], x[1], x[2]) + t * Eigen::Vector3d(e[0], e[1], e[2]);
      }
      else
      {
        ++fallbacks;
        // The node lies on the surface (within the locator's tolerance):
        // look back from the outside neighbour.
        const double xo[3] = { x[0] + h * e[0], x[1] + h * e[1], x[2] + h * e[2] };
        const double back[3] = { -e[0], -e[1], -e[2] };
        if (caster.FirstHit(xo, back, reach, t, triangle))
        {
          d = h - t;
          hit = Eigen::Vector3d(xo[0], xo[1], xo[2]) - t * Eigen::Vector3d(e[0], e[1], e[2]);
        }
        else
        {
          // Last resort: the nearest boundary triangle.
          const Eigen::Vector3d p(x[0], x[1], x[2]);
          double best = std::numeric_limits<double>::infinity();
          for (int f = 0; f < numTriangles; ++f)
          {
            double weights[3];
            const Eigen::Vector3d q =
              ClosestPointOnTriangle(p, vertex(f, 0), vertex(f, 1), vertex(f, 2), weights);
            const double dist = (q - p).squaredNorm();
            if (dist < best)
            {
              best = dist;
              triangle = f;
              hit = q;
            }
          }
          d = std::sqrt(best);
        }
      }
      node.Distance = std::clamp(d, MinDistanceFraction * h, h);
      node.Triangle = triangle;
      if (triangle >= 0)
      {
        const Eigen::Vector3d a = vertex(triangle, 0), bb = vertex(triangle, 1),
                              c = vertex(triangle, 2);
        const Eigen::Vector3d normal = (bb - a).cross(c - a);
        const double norm = normal.norm();
        node.Cosine = norm > 0.0 ? std::abs(normal[Axis[dir]]) / norm : 1.0;
        TriangleWeights(hit, a, bb, c, node.Weights);
      }
    }
  }
  return fallbacks;
}

/// BuildLevel, 4. Probes of the normal derivative at the boundary nodes. Where the
/// link is along the normal (|e . n| = 1 to rounding) the interior node of
/// the link itself, at delta = d (polygrid eq. 9). Elsewhere the link is
/// not along the normal and (phi_b - phi_i) / delta would miss the
/// tangential gradient (an O(1) error on slanted faces), so phi is read at
/// x_b - l n, l = h, 1.5 h, ... 3 h, by trilinear interpolation in the
/// first grid cell there whose 8 corners are interior nodes; if none is,
/// the interior node of the link after all.
void PlaceProbes(const TetMesh& mesh, int threads, GridLevel& level)
{
  const int nx = level.Dims[0];
  const int ny = level.Dims[1];
  const int nz = level.Dims[2];
  const double h = level.Spacing;
  const int numInterior = static_cast<int>(level.InteriorGrid.size());
  const int* unknown = level.NodeUnknown.data();
  const int numBoundary = static_cast<int>(level.Boundary.size());
  auto vertex = [&mesh](int f, int m) { return TriangleVertex(mesh, f, m); };
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int b = 0; b < numBoundary; ++b)
  {
    GridLevel::BoundaryNode& node = level.Boundary[b];
    node.ProbeCount = 1;
    node.ProbeNodes[0] = node.Interior;
    node.ProbeWeights[0] = 1.0;
    node.Probe = node.Distance * node.Cosine;
    if (node.Triangle < 0 || node.Cosine >= 1.0 - 1e-12)
    {
      continue;
    }
    const Eigen::Vector3d a = vertex(node.Triangle, 0), bb = vertex(node.Triangle, 1),
                          c = vertex(node.Triangle, 2);
    const Eigen::Vector3d normal = (bb - a).cross(c - a).normalized();
    double xb[3];
    level.Position(numInterior + b, xb);
    auto cornerUnknown = [&](const int ci[3])
    {
      if (ci[0] < 0 || ci[1] < 0 || ci[2] < 0 || ci[0] >= nx || ci[1] >= ny || ci[2] >= nz)
      {
        return -1;
      }
      return unknown[ci[0] + static_cast<size_t>(nx) * (ci[1] + static_cast<size_t>(ny) * ci[2])];
    };
    int found = 0;
    int nodes[8];
    double weights[8];
    const int numDepths = static_cast<int>(std::size(ProbeDepths));
    for (int attempt = 0; attempt < 2 * numDepths && !found; ++attempt)
    {
      // Trilinear in the cell at each depth first, then a linear
      // interpolation in one of the tets of the cell (Kuhn split about each
      // of its 4 main diagonals), which needs only 4 interior corners.
      const bool tetrahedral = attempt >= numDepths;
      const double depth = h * ProbeDepths[attempt % numDepths];
      int i0[3];
      double t[3];
      for (int d = 0; d < 3; ++d)
      {
        const double f = (xb[d] - depth * normal[d] - level.Origin[d]) / h;
        i0[d] = static_cast<int>(std::floor(f));
        t[d] = f - i0[d];
      }
      if (!tetrahedral)
      {
        bool all = true;
        for (int k = 0; k < 8 && all; ++k)
        {
          const int ci[3] = { i0[0] + (k & 1), i0[1] + ((k >> 1) & 1), i0[2] + ((k >> 2) & 1) };
          nodes[k] = cornerUnknown(ci);
          weights[k] = ((k & 1) ? t[0] : 1.0 - t[0]) * (((k >> 1) & 1) ? t[1] : 1.0 - t[1]) *
            (((k >> 2) & 1) ? t[2] : 1.0 - t[2]);
          all = nodes[k] >= 0;
        }
        if (all)
        {
          found = 8;
          node.Probe = depth;
        }
        continue;
      }
      for (int flip = 0; flip < 4 && !found; ++flip)
      {
        // Reflect axes x (flip & 1) and y (flip & 2): the diagonal from the
        // reflected origin corner. Sort the local coordinates descending:
        // the tet 0 -> e_p0 -> e_p0 + e_p1 -> (1, 1, 1) holds the point with
        // weights 1 - s0, s0 - s1, s1 - s2, s2.
        const bool reflect[3] = { (flip & 1) != 0, (flip & 2) != 0, false };
        double sLocal[3];
        for (int d = 0; d < 3; ++d)
        {
          sLocal[d] = reflect[d] ? 1.0 - t[d] : t[d];
        }
        int p[3] = { 0, 1, 2 };
        std::sort(p,
          p + 3,
          [&](int u, int v) { return sLocal[u] > sLocal[v] || (sLocal[u] == sLocal[v] && u < v); });
        int corner[3] = { 0, 0, 0 };
        const double w[4] = {
          1.0 - sLocal[p[0]], sLocal[p[0]] - sLocal[p[1]], sLocal[p[1]] - sLocal[p[2]], sLocal[p[2]]
        };
        bool all = true;
        for (int k = 0; k < 4 && all; ++k)
        {
          if (k > 0)
          {
            corner[p[k - 1]] = 1;
          }
          int ci[3];
          for (int d = 0; d < 3; ++d)
          {
            ci[d] = i0[d] + (reflect[d] ? 1 - corner[d] : corner[d]);
          }
          nodes[k] = cornerUnknown(ci);
          weights[k] = w[k];
          all = nodes[k] >= 0;
        }
        if (all)
        {
          found = 4;
          node.Probe = depth;
        }
      }
    }
    if (found)
    {
      // Sorted by node id (CSR columns): insertion sort of the 4 or 8.
      for (int k = 0; k < found; ++k)
      {
        int m = k;
        while (m > 0 && nodes[m - 1] > nodes[m])
        {
          std::swap(nodes[m - 1], nodes[m]);
          std::swap(weights[m - 1], weights[m]);
          --m;
        }
      }
      for (int k = 0; k < found; ++k)
      {
        node.ProbeNodes[k] = nodes[k];
        node.ProbeWeights[k] = weights[k];
      }
      node.ProbeCount = found;
    }
  }
}

/// BuildLevel, 5. Neighbours, CSR pattern and the slot of each direction in
/// its row.
void BuildLevelPattern(int threads, GridLevel& level)
{
  const int numInterior = static_cast<int>(level.InteriorGrid.size());
  const int numBoundary = static_cast<int>(level.Boundary.size());
  auto neighbourUnknown = [&level](const int ijk[3], int dir)
  { return NeighbourUnknown(level, ijk, dir); };
  const int numUnknowns = numInterior + numBoundary;
  level.Neighbours.resize(6 * static_cast<size_t>(numInterior));
  level.Slots.resize(7 * static_cast<size_t>(numInterior));
  DiffusionSystem& system = level.System;
  system.NumberOfUnknowns = numUnknowns;
  system.RowOffsets.resize(static_cast<size_t>(numUnknowns) + 1);
  // Interior rows have 7 entries; boundary rows their probe nodes and themselves.
  for (int u = 0; u <= numInterior; ++u)
  {
    system.RowOffsets[u] = 7 * u;
  }
  for (int b = 0; b < numBoundary; ++b)
  {
    system.RowOffsets[numInterior + b + 1] =
      system.RowOffsets[numInterior + b] + level.Boundary[b].ProbeCount + 1;
  }
  const size_t nnz = static_cast<size_t>(system.RowOffsets[numUnknowns]);
  system.ColumnIndices.resize(nnz);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int u = 0; u < numInterior; ++u)
  {
    int ijk[3];
    level.InteriorIndex(u, ijk);
    int b = level.BoundaryOffsets[u];
    int columns[7], order[7];
    for (int dir = 0; dir < 6; ++dir)
    {
      int v = neighbourUnknown(ijk, dir);
      if (v < 0)
      {
        v = numInterior + b++;
      }
      level.Neighbours[6 * static_cast<size_t>(u) + dir] = v;
      columns[dir] = v;
    }
    columns[6] = u;
    for (int k = 0; k < 7; ++k)
    {
      order[k] = k;
    }
    std::sort(order, order + 7, [&](int a, int c) { return columns[a] < columns[c]; });
    const size_t row = 7 * static_cast<size_t>(u);
    for (int k = 0; k < 7; ++k)
    {
      system.ColumnIndices[row + k] = columns[order[k]];
      level.Slots[row + order[k]] = static_cast<std::uint8_t>(k);
    }
  }
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int b = 0; b < numBoundary; ++b)
  {
    const GridLevel::BoundaryNode& node = level.Boundary[b];
    const size_t row = static_cast<size_t>(system.RowOffsets[numInterior + b]);
    for (int k = 0; k < node.ProbeCount; ++k)
    {
      system.ColumnIndices[row + k] = node.ProbeNodes[k]; // sorted, all < numInterior + b
    }
    system.ColumnIndices[row + node.ProbeCount] = numInterior + b;
  }
}

/// BuildLevel, 6. Relaxation colours: parity of i + j + k for interior nodes (their
/// interior neighbours have the other parity), boundary nodes last (they
/// are coupled to interior nodes only).
/// The level's solutions are cleared.
void ColourNodes(GridLevel& level)
{
  const int numInterior = static_cast<int>(level.InteriorGrid.size());
  const int numBoundary = static_cast<int>(level.Boundary.size());
  for (auto& colour : level.Colours)
  {
    colour.clear();
  }
  for (int u = 0; u < numInterior; ++u)
  {
    int ijk[3];
    level.InteriorIndex(u, ijk);
    level.Colours[(ijk[0] + ijk[1] + ijk[2]) & 1].push_back(u);
  }
  level.Colours[2].resize(static_cast<size_t>(numBoundary));
  for (int b = 0; b < numBoundary; ++b)
  {
    level.Colours[2][b] = numInterior + b;
  }
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    level.Solution[c].resize(0);
  }
}

} // namespace

int GridSolver::BuildLevel(const TetMesh& mesh, GridLevel& level) const
{
  const long long numNodes =
    static_cast<long long>(level.Dims[0]) * level.Dims[1] * level.Dims[2];
  // Locating a node and casting rays cost ~10 relaxation rows.
  const int threads = Threads(10 * numNodes);
  LocateNodes(Locator_, threads, level);
  const int fallbacks = PlaceBoundaryNodes(mesh, Caster_, threads, level);
  PlaceProbes(mesh, threads, level);
  BuildLevelPattern(threads, level);
  ColourNodes(level);
  return fallbacks;
}

// ---- assembly ----

void GridSolver::Assemble(const TetMesh& mesh, const OpticalProperties& material, int levelIndex)
{
  GridLevel& level = Levels_[levelIndex];
  const int threads = Threads(level.NumberOfUnknowns());
  const int numInterior = level.NumberOfInterior();
  const int numBoundary = level.NumberOfBoundary();
  const double h = level.Spacing;
  const double h2 = h * h;

  // Interior material: the containing tet's (fine level), or the mean of the
  // interior children (coarse levels; polygrid Sec. 5.3).
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    level.Mu[c].resize(static_cast<size_t>(numInterior));
    level.Kappa[c].resize(static_cast<size_t>(numInterior));
    level.BoundaryKappa[c].resize(static_cast<size_t>(numBoundary));
  }
  level.BoundaryRobin.resize(static_cast<size_t>(numBoundary));
  level.BoundaryScale.resize(static_cast<size_t>(numBoundary));
  const GridLevel* finer = levelIndex > 0 ? &Levels_[levelIndex - 1] : nullptr;
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int u = 0; u < numInterior; ++u)
  {
    double mu[NumberOfChannels] = { 0, 0, 0 }, kappa[NumberOfChannels] = { 0, 0, 0 };
    int children = 0;
    if (finer)
    {
      int ijk[3];
      level.InteriorIndex(u, ijk);
      for (int child = 0; child < 8; ++child)
      {
        const int f[3] = {
          2 * ijk[0] + (child & 1), 2 * ijk[1] + ((child >> 1) & 1), 2 * ijk[2] + ((child >> 2) & 1)
        };
        if (f[0] >= finer->Dims[0] || f[1] >= finer->Dims[1] || f[2] >= finer->Dims[2])
        {
          continue;
        }
        const int v = finer->NodeUnknown[f[0] +
          static_cast<size_t>(finer->Dims[0]) *
            (f[1] + static_cast<size_t>(finer->Dims[1]) * f[2])];
        if (v < 0)
        {
          continue;
        }
        ++children;
        for (int c = 0; c < NumberOfChannels; ++c)
        {
          mu[c] += finer->Mu[c][v];
          kappa[c] += finer->Kappa[c][v];
        }
      }
    }
    const int t = level.InteriorTet[u];
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      if (children > 0)
      {
        level.Mu[c][u] = mu[c] / children;
        level.Kappa[c][u] = kappa[c] / children;
      }
      else
      {
        level.Mu[c][u] = material.AbsorptionCoefficient[3 * static_cast<size_t>(t) + c];
        level.Kappa[c][u] = material.Kappa(t, c);
      }
    }
  }
  // Boundary nodes: kappa, A and Fdr of the tet owning the hit triangle.
  const std::vector<int>& owners = mesh.GetBoundaryTriangleTets();
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int b = 0; b < numBoundary; ++b)
  {
    const GridLevel::BoundaryNode& node = level.Boundary[b];
    const int t = owners[node.Triangle];
    const double eta = material.RefractiveIndex[t];
    const double fdr = Fresnel::DiffuseReflectance(eta);
    const double a = Fresnel::MismatchA(eta);
    level.BoundaryRobin[b] = node.Probe / (2.0 * a);
    level.BoundaryScale[b] = 4.0 / (1.0 - fdr);
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      level.BoundaryKappa[c][b] = material.Kappa(t, c);
    }
  }

  // Matrix and right-hand side.
  DiffusionSystem& system = level.System;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    system.Values[c].resize(system.ColumnIndices.size());
    system.RightHandSide[c].resize(level.NumberOfUnknowns());
  }
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int u = 0; u < numInterior; ++u)
  {
    const int* neighbours = &level.Neighbours[6 * static_cast<size_t>(u)];
    const std::uint8_t* slots = &level.Slots[7 * static_cast<size_t>(u)];
    double dist[6];
    for (int dir = 0; dir < 6; ++dir)
    {
      const int v = neighbours[dir];
      dist[dir] = v < numInterior ? h : level.Boundary[v - numInterior].Distance;
    }
    const size_t row = 7 * static_cast<size_t>(u);
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      double* values = system.Values[c].data() + row;
      const double ku = level.Kappa[c][u];
      double diagonal = h2 * level.Mu[c][u];
      for (int dir = 0; dir < 6; ++dir)
      {
        const int v = neighbours[dir];
        const double kv =
          v < numInterior ? level.Kappa[c][v] : level.BoundaryKappa[c][v - numInterior];
        const double link = 2.0 * ku * kv / (ku + kv); // harmonic mean on the link
        // Polygrid eq. 9 / Appendix B weight for axis-aligned neighbours at
        // h+ and h-: w = 2 / (h_dir (h+ + h-)); times kappa on the link
        // (Stam's eq. 8 in flux form) and h^2.
        const double w = h2 * 2.0 * link / (dist[dir] * (dist[dir & ~1] + dist[dir | 1]));
        values[slots[dir]] = -w;
        diagonal += w;
      }
      values[slots[6]] = diagonal;
      system.RightHandSide[c][u] = 0.0;
    }
  }
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int b = 0; b < numBoundary; ++b)
  {
    const GridLevel::BoundaryNode& node = level.Boundary[b];
    const size_t row = static_cast<size_t>(system.RowOffsets[numInterior + b]);
    const double robin = level.BoundaryRobin[b];
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      // Polygrid eq. 9, boundary row, with the normal derivative
      // (phi_b - phi_p) / l (l = delta and phi_p = phi_i on links along the
      // normal), times l/(2A):
      // (l/(2A) + kappa_b) phi_b - kappa_b phi_p = l/(2A) 4 q_b / (1 - Fdr).
      const double kb = level.BoundaryKappa[c][b];
      for (int k = 0; k < node.ProbeCount; ++k)
      {
        system.Values[c][row + k] = -kb * node.ProbeWeights[k];
      }
      system.Values[c][row + node.ProbeCount] = kb + robin;
      system.RightHandSide[c][numInterior + b] =
        robin * level.BoundaryScale[b] * level.BoundarySource[c][b];
    }
  }
}

void GridSolver::AddInteriorSources(int levelIndex, const std::vector<PlacedSource>& sources)
{
  if (sources.empty())
  {
    return;
  }
  GridLevel& level = Levels_[levelIndex];
  std::vector<double> power(3 * static_cast<size_t>(level.NumberOfInterior()), 0.0);
  DistributeSources(level, sources, power);
  // The interior rows are the balance of the node's control volume (the
  // box of extents (h+ + h-)/2 around it) divided by its volume, times h^2:
  // the source term is the node's power / V, times h^2.
  const double h2 = level.Spacing * level.Spacing;
  for (int u = 0; u < level.NumberOfInterior(); ++u)
  {
    const double* p = &power[3 * static_cast<size_t>(u)];
    if (p[0] == 0.0 && p[1] == 0.0 && p[2] == 0.0)
    {
      continue;
    }
    double extent[3];
    level.ControlExtents(u, extent);
    const double volume = extent[0] * extent[1] * extent[2];
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      level.System.RightHandSide[c][u] += h2 * p[c] / volume;
    }
  }
}

// ---- solve ----

void GridSolver::CheckProblem(const DiffusionProblem& problem, bool needIrradiance) const
{
  if (!problem.Mesh || !problem.Material || (needIrradiance && !problem.Irradiance))
  {
    throw Error(std::string("grid: the problem needs a mesh, a material") +
      (needIrradiance ? " and an irradiance" : ""));
  }
  const TetMesh& mesh = *problem.Mesh;
  ComputeSpacing(mesh); // empty mesh, bad spacing
  problem.Material->Validate(mesh.GetNumberOfTets());
  if (needIrradiance)
  {
    const std::vector<double>& q = *problem.Irradiance;
    const size_t expected = 3 * static_cast<size_t>(mesh.GetNumberOfPoints());
    if (q.size() != expected)
    {
      std::ostringstream os;
      os << "grid: Irradiance has " << q.size() << " values but the mesh has "
         << mesh.GetNumberOfPoints() << " points (" << expected << " values expected, 3 per point)";
      throw Error(os.str());
    }
    for (size_t k = 0; k < q.size(); ++k)
    {
      if (!(std::isfinite(q[k]) && q[k] >= 0.0))
      {
        std::ostringstream os;
        os << "grid: Irradiance of point " << k / 3 << ", channel " << ChannelNames[k % 3] << " is "
           << q[k] << " W/mm^2: must be finite and >= 0";
        throw Error(os.str());
      }
    }
  }
}

bool GridSolver::Solve(const DiffusionProblem& problem,
  std::vector<double>& fluence,
  SolverReport& report)
{
  RequireSurfaceCollimatedModel(problem, "grid");
  return SolveImpl(problem, nullptr, fluence, report);
}

bool GridSolver::SolveWithNodeIrradiance(const DiffusionProblem& problem,
  const std::vector<double>& nodeIrradiance,
  std::vector<double>& fluence,
  SolverReport& report)
{
  RequireSurfaceCollimatedModel(problem, "grid");
  return SolveImpl(problem, &nodeIrradiance, fluence, report);
}

bool GridSolver::SolveLevel(GridLevel& level,
  bool guess,
  std::array<int, NumberOfChannels>& iterations,
  std::array<double, NumberOfChannels>& residual,
  std::array<bool, NumberOfChannels>& converged,
  double progressStart,
  double progressEnd)
{
  // The solver of the registry (LinearSolver.h) chosen in SolveImpl; the
  // relaxation sweeps the level's colours (Gauss-Seidel).
  ChannelLinearSolver& linear = *Linear_;
  linear.SetRelTol(RelTol_);
  linear.SetMaxIter(MaxIter_);
  linear.SetNumberOfThreads(Threads(level.NumberOfUnknowns()));
  if (auto* relaxation = dynamic_cast<RelaxationSolver*>(&linear))
  {
    relaxation->SetColours(level.Colours, static_cast<int>(std::size(level.Colours)));
  }
  linear.SetProgressCallback([this, progressStart, progressEnd](double fraction)
    { return ReportProgress(progressStart + (progressEnd - progressStart) * fraction); });
  std::array<LinearSolveStats, NumberOfChannels> stats;
  const bool done = linear.Solve(level.System, level.Solution, guess, stats);
  linear.SetProgressCallback(nullptr);
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    iterations[c] = stats[c].Iterations;
    residual[c] = stats[c].RelativeResidual;
    converged[c] = stats[c].Converged;
  }
  return done;
}

namespace
{
/// SolveImpl: the node irradiance given by the caller, checked (3 finite
/// values >= 0 per boundary node).
void CheckNodeIrradiance(const std::vector<double>* nodeIrradiance, int numBoundary)
{
  const size_t expected = 3 * static_cast<size_t>(numBoundary);
  if (nodeIrradiance->size() != expected)
  {
    std::ostringstream os;
    os << "grid: the node irradiance has " << nodeIrradiance->size()
       << " values but the grid has " << numBoundary << " boundary nodes (" << expected
       << " values expected, 3 per node)";
    throw Error(os.str());
  }
  for (size_t k = 0; k < expected; ++k)
  {
    const double v = (*nodeIrradiance)[k];
    if (!(std::isfinite(v) && v >= 0.0))
    {
      std::ostringstream os;
      os << "grid: node irradiance of boundary node " << k / 3 << ", channel "
         << ChannelNames[k % 3] << " is " << v << " W/mm^2: must be finite and >= 0";
      throw Error(os.str());
    }
  }
}

/// SolveImpl: the fine level's sources, q at the boundary nodes (given, or
/// interpolated on the hit triangle from the problem's Irradiance).
void SetFineSources(const DiffusionProblem& problem, const std::vector<double>* nodeIrradiance,
  int threads, GridLevel& fine)
{
  const TetMesh& mesh = *problem.Mesh;
  const int numBoundary = fine.NumberOfBoundary();
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    fine.BoundarySource[c].resize(static_cast<size_t>(numBoundary));
  }
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int b = 0; b < numBoundary; ++b)
  {
    const GridLevel::BoundaryNode& node = fine.Boundary[b];
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      double q = 0.0;
      if (nodeIrradiance)
      {
        q = (*nodeIrradiance)[3 * static_cast<size_t>(b) + c];
      }
      else
      {
        // Linear (barycentric) interpolation on the hit triangle.
        for (int m = 0; m < 3; ++m)
        {
          q += node.Weights[m] *
            (*problem.Irradiance)[3 * static_cast<size_t>(triangles[3 * node.Triangle + m]) + c];
        }
      }
      fine.BoundarySource[c][b] = q;
    }
  }
}

/// SolveImpl: the sources of a coarse level: mean q of the children's
/// boundary nodes on the same side; else of all their boundary nodes; else
/// the mean of the level.
void RestrictSources(const GridLevel& finer, int threads, GridLevel& level)
{
  const int nb = level.NumberOfBoundary();
  double mean[NumberOfChannels] = { 0, 0, 0 };
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    for (double q : finer.BoundarySource[c])
    {
      mean[c] += q;
    }
    mean[c] /= std::max(1, finer.NumberOfBoundary());
    level.BoundarySource[c].resize(static_cast<size_t>(nb));
  }
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int b = 0; b < nb; ++b)
  {
    const GridLevel::BoundaryNode& node = level.Boundary[b];
    int ijk[3];
    level.InteriorIndex(node.Interior, ijk);
    double same[NumberOfChannels] = { 0, 0, 0 }, any[NumberOfChannels] = { 0, 0, 0 };
    int numSame = 0, numAny = 0;
    for (int child = 0; child < 8; ++child)
    {
      const int f[3] = { 2 * ijk[0] + (child & 1),
        2 * ijk[1] + ((child >> 1) & 1),
        2 * ijk[2] + ((child >> 2) & 1) };
      if (f[0] >= finer.Dims[0] || f[1] >= finer.Dims[1] || f[2] >= finer.Dims[2])
      {
        continue;
      }
      const int v = finer.NodeUnknown[f[0] +
        static_cast<size_t>(finer.Dims[0]) *
          (f[1] + static_cast<size_t>(finer.Dims[1]) * f[2])];
      if (v < 0)
      {
        continue;
      }
      for (int fb = finer.BoundaryOffsets[v]; fb < finer.BoundaryOffsets[v + 1]; ++fb)
      {
        const bool sameSide = finer.Boundary[fb].Direction == node.Direction;
        numSame += sameSide;
        ++numAny;
        for (int c = 0; c < NumberOfChannels; ++c)
        {
          any[c] += finer.BoundarySource[c][fb];
          same[c] += sameSide ? finer.BoundarySource[c][fb] : 0.0;
        }
      }
    }
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      level.BoundarySource[c][b] =
        numSame > 0 ? same[c] / numSame : (numAny > 0 ? any[c] / numAny : mean[c]);
    }
  }
}

/// SolveImpl, prolongation: the coarse solution interpolated at the finer
/// level's nodes.
void Prolongate(const GridLevel& coarse, int threads, GridLevel& finer)
{
  const int n = finer.NumberOfUnknowns();
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    finer.Solution[c].resize(n);
  }
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int u = 0; u < n; ++u)
  {
    double x[3], value[NumberOfChannels];
    finer.Position(u, x);
    EvaluateLevel(coarse, x, value);
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      finer.Solution[c][u] = value[c];
    }
  }
}
} // namespace


bool GridSolver::SolveImpl(const DiffusionProblem& problem,
  const std::vector<double>* nodeIrradiance,
  std::vector<double>& fluence,
  SolverReport& report)
{
  const DynamicThreads dynamic(NumberOfThreads_ <= 0);
  CheckProblem(problem, nodeIrradiance == nullptr);
  // The linear solver from the registry's non-symmetric entries (throws
  // "grid: unknown linear solver 'x' (known: bicgstab, relaxation)").
  Linear_ = CreateNonSymmetricLinearSolver(LinearSolver_, "grid");
  const std::string solverName = Linear_->GetName();
  const TetMesh& mesh = *problem.Mesh;
  const OpticalProperties& material = *problem.Material;
  report = SolverReport();
  report.Solver = GetName();
  report.LinearSolver = solverName;

  // Interior sources placed first: a source outside the object is an error
  // (Sources::Place, the vertex solvers' messages) before any work.
  std::vector<PlacedSource> placed;
  if (problem.HasInteriorSources())
  {
    placed = problem.InteriorSources->Place(mesh, material);
  }

  auto start = Clock::now();
  PrepareGrid(mesh);
  GridLevel& fine = Levels_[0];
  const int numInterior = fine.NumberOfInterior();
  const int numBoundary = fine.NumberOfBoundary();
  const int threads = Threads(std::max(fine.NumberOfUnknowns(), mesh.GetNumberOfPoints()));
  if (nodeIrradiance)
  {
    CheckNodeIrradiance(nodeIrradiance, numBoundary);
  }
  // Fine-level sources: q at the boundary nodes.
  SetFineSources(problem, nodeIrradiance, threads, fine);
  Assemble(mesh, material, 0);
  AddInteriorSources(0, placed);
  const bool multi = MultiLevel_ && Levels_.size() > 1;
  const bool warm = WarmStart_ && HaveSolution_;
  const bool useCoarse = multi && !warm;
  if (useCoarse)
  {
    for (size_t l = 1; l < Levels_.size(); ++l)
    {
      // Coarse sources: mean q of the children's boundary nodes on the same
      // side; else of all their boundary nodes; else the mean of the level.
      RestrictSources(Levels_[l - 1], threads, Levels_[l]);
      Assemble(mesh, material, static_cast<int>(l));
      AddInteriorSources(static_cast<int>(l), placed);
    }
  }
  report.SetupMilliseconds = MillisecondsSince(start);

  start = Clock::now();
  CoarseIterations_.fill(0);
  std::array<double, NumberOfChannels> residual{};
  std::array<bool, NumberOfChannels> converged{};
  std::array<int, NumberOfChannels> iterations{};
  const double fineShare = useCoarse ? 0.5 : 1.0;
  if (useCoarse)
  {
    // Coarsest first; each solution initialises the next finer level.
    const int last = static_cast<int>(Levels_.size()) - 1;
    for (int l = last; l >= 1; --l)
    {
      const double from = 0.5 * (last - l) / last, to = 0.5 * (last - l + 1) / last;
      if (!SolveLevel(Levels_[l], l < last, iterations, residual, converged, from, to))
      {
        HaveSolution_ = false;
        return false;
      }
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        CoarseIterations_[c] += iterations[c];
      }
      // Prolongation: interpolate at the finer level's nodes.
      Prolongate(Levels_[l], threads, Levels_[l - 1]);
    }
  }
  if (!SolveLevel(fine, warm || useCoarse, iterations, residual, converged, 1.0 - fineShare, 1.0))
  {
    HaveSolution_ = false;
    return false;
  }
  HaveSolution_ = true;
  ReportProgress(1.0);
  report.SolveMilliseconds = MillisecondsSince(start);

  // Fluence at the mesh points.
  const int numPoints = mesh.GetNumberOfPoints();
  fluence.resize(3 * static_cast<size_t>(numPoints));
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int i = 0; i < numPoints; ++i)
  {
    EvaluateLevel(fine, mesh.GetPoint(i), &fluence[3 * static_cast<size_t>(i)]);
  }

  report.NumberOfUnknowns = numInterior + numBoundary;
  report.NumberOfNonZeros = static_cast<long long>(fine.System.ColumnIndices.size());
  std::size_t bytes = 0;
  for (const GridLevel& level : Levels_)
  {
    bytes += level.MemoryBytes();
  }
  // Work vectors of the linear solver (BiCGSTAB: 9; relaxation: none).
  if (GetLinearSolverRegistry().Get(solverName).Properties.Krylov == "bicgstab")
  {
    bytes += 9 * static_cast<std::size_t>(fine.NumberOfUnknowns()) * sizeof(double);
  }
  report.MemoryBytes = bytes;
  report.Iterations = iterations;
  report.Residual = residual;
  report.Converged = converged;
  return true;
}

} // namespace translucency
