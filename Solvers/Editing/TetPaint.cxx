#include "TetPaint.h"

#include "Error.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace translucency
{

namespace
{

/// Uniform grid over the stroke points, cell size >= the cut-off radius, so
/// every stroke point within R of x lies in the 27 grid cells around x.
struct StrokeGrid
{
  double Origin[3] = { 0, 0, 0 };
  double Spacing = 1.0;
  int Dims[3] = { 1, 1, 1 };
  std::vector<int> Offsets; ///< CSR over grid cells
  std::vector<int> Points;  ///< stroke point ids per grid cell

  void Build(const std::vector<double>& stroke, double radius)
  {
    const size_t n = stroke.size() / 3;
    double hi[3];
    for (int a = 0; a < 3; ++a)
    {
      Origin[a] = hi[a] = stroke[a];
    }
    for (size_t s = 1; s < n; ++s)
    {
      for (int a = 0; a < 3; ++a)
      {
        Origin[a] = std::min(Origin[a], stroke[3 * s + a]);
        hi[a] = std::max(hi[a], stroke[3 * s + a]);
      }
    }
    // Few grid cells per stroke point: double the spacing until it fits.
    const double maxCells = std::max(4096.0, 8.0 * static_cast<double>(n));
    Spacing = radius;
    for (;;)
    {
      double cells = 1.0;
      for (int a = 0; a < 3; ++a)
      {
        cells *= std::floor((hi[a] - Origin[a]) / Spacing) + 1.0;
      }
      if (cells <= maxCells)
      {
        break;
      }
      Spacing *= 2.0;
    }
    for (int a = 0; a < 3; ++a)
    {
      Dims[a] = static_cast<int>(std::floor((hi[a] - Origin[a]) / Spacing)) + 1;
    }
    const size_t numCells = static_cast<size_t>(Dims[0]) * Dims[1] * Dims[2];
    Offsets.assign(numCells + 1, 0);
    std::vector<int> cellOf(n);
    for (size_t s = 0; s < n; ++s)
    {
      int ijk[3];
      for (int a = 0; a < 3; ++a)
      {
        ijk[a] = std::min(Dims[a] - 1,
          std::max(0, static_cast<int>(std::floor((stroke[3 * s + a] - Origin[a]) / Spacing))));
      }
      cellOf[s] = (ijk[2] * Dims[1] + ijk[1]) * Dims[0] + ijk[0];
      ++Offsets[cellOf[s] + 1];
    }
    for (size_t k = 0; k < numCells; ++k)
    {
      Offsets[k + 1] += Offsets[k];
    }
    Points.resize(n);
    std::vector<int> fill(Offsets.begin(), Offsets.end() - 1);
    for (size_t s = 0; s < n; ++s)
    {
      Points[fill[cellOf[s]]++] = static_cast<int>(s);
    }
  }

  /// Smallest squared distance from x to the stroke points of the 27 grid
  /// cells around x (+infinity if none).
  double NearestSquared(const double* x, const double* stroke) const
  {
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a)
    {
      const double f = std::floor((x[a] - Origin[a]) / Spacing);
      const int c = static_cast<int>(std::max(-2.0, std::min(f, static_cast<double>(Dims[a]) + 1)));
      lo[a] = std::max(0, c - 1);
      hi[a] = std::min(Dims[a] - 1, c + 1);
    }
    double d2 = std::numeric_limits<double>::infinity();
    for (int k = lo[2]; k <= hi[2]; ++k)
    {
      for (int j = lo[1]; j <= hi[1]; ++j)
      {
        const int row = (k * Dims[1] + j) * Dims[0];
        for (int cell = row + lo[0]; cell <= row + hi[0]; ++cell)
        {
          for (int m = Offsets[cell]; m < Offsets[cell + 1]; ++m)
          {
            const double* p = stroke + 3 * static_cast<size_t>(Points[m]);
            const double dx = x[0] - p[0], dy = x[1] - p[1], dz = x[2] - p[2];
            const double e = dx * dx + dy * dy + dz * dz;
            d2 = e < d2 ? e : d2;
          }
        }
      }
    }
    return d2;
  }
};

} // namespace

std::vector<double> TetPaint::SamplePolyline(
  const std::vector<double>& points, double spacing, std::int64_t maximumPoints)
{
  if (!(spacing > 0.0) || !std::isfinite(spacing))
  {
    std::ostringstream os;
    os << "TetPaint: the stroke sample spacing " << spacing << " mm must be finite and > 0";
    throw Error(os.str());
  }
  if (points.size() % 3 != 0)
  {
    std::ostringstream os;
    os << "TetPaint: " << points.size() << " stroke coordinates: not 3 per point";
    throw Error(os.str());
  }
  for (size_t k = 0; k < points.size(); ++k)
  {
    if (!std::isfinite(points[k]))
    {
      std::ostringstream os;
      os << "TetPaint: stroke point " << k / 3 << " has the coordinate " << points[k]
         << ": must be finite";
      throw Error(os.str());
    }
  }
  const size_t n = points.size() / 3;
  // Pieces per segment first, so that the size is checked before any allocation.
  std::vector<double> pieces(n > 0 ? n - 1 : 0);
  double total = static_cast<double>(n);
  for (size_t i = 0; i + 1 < n; ++i)
  {
    const double* a = &points[3 * i];
    const double* b = &points[3 * i + 3];
    const double length =
      std::sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) +
        (b[2] - a[2]) * (b[2] - a[2]));
    pieces[i] = std::max(1.0, std::ceil(length / spacing));
    total += pieces[i] - 1.0;
  }
  if (total > static_cast<double>(maximumPoints))
  {
    std::ostringstream os;
    os << "TetPaint: sampling the stroke every " << spacing << " mm gives " << total
       << " points, more than " << maximumPoints
       << ": shorten the stroke or widen the brush";
    throw Error(os.str());
  }
  std::vector<double> samples;
  samples.reserve(3 * static_cast<size_t>(total));
  for (size_t i = 0; i < n; ++i)
  {
    const double* a = &points[3 * i];
    samples.insert(samples.end(), a, a + 3);
    if (i + 1 == n)
    {
      break;
    }
    const double* b = &points[3 * i + 3];
    const int m = static_cast<int>(pieces[i]);
    for (int j = 1; j < m; ++j)
    {
      const double t = static_cast<double>(j) / m;
      for (int c = 0; c < 3; ++c)
      {
        samples.push_back(a[c] + t * (b[c] - a[c]));
      }
    }
  }
  return samples;
}

void TetPaint::Validate() const
{
  if (Stroke_.empty() || Stroke_.size() % 3 != 0)
  {
    std::ostringstream os;
    os << "TetPaint: " << Stroke_.size()
       << " stroke coordinates: need at least one stroke point (3 coordinates each, mm)";
    throw Error(os.str());
  }
  for (size_t k = 0; k < Stroke_.size(); ++k)
  {
    if (!std::isfinite(Stroke_[k]))
    {
      std::ostringstream os;
      os << "TetPaint: stroke point " << k / 3 << " has the coordinate " << Stroke_[k]
         << ": must be finite";
      throw Error(os.str());
    }
  }
  if (!(Width_ >= 0.0) || !std::isfinite(Width_))
  {
    std::ostringstream os;
    os << "TetPaint: the width " << Width_ << " mm must be finite and >= 0";
    throw Error(os.str());
  }
  if (!(Strength_ >= 0.0 && Strength_ <= 1.0))
  {
    std::ostringstream os;
    os << "TetPaint: the strength " << Strength_ << " must be in [0, 1]";
    throw Error(os.str());
  }
  if (!(CutoffWeight_ >= 0.0 && CutoffWeight_ <= 1.0))
  {
    std::ostringstream os;
    os << "TetPaint: the cut-off weight " << CutoffWeight_ << " must be in [0, 1]";
    throw Error(os.str());
  }
  for (int c = 0; c < 3; ++c)
  {
    if (!std::isfinite(TargetAbsorption_[c]) || !std::isfinite(TargetScattering_[c]))
    {
      std::ostringstream os;
      os << "TetPaint: the target of channel " << "RGB"[c] << " is not finite (mu_a "
         << TargetAbsorption_[c] << ", sigma_s' " << TargetScattering_[c] << ")";
      throw Error(os.str());
    }
  }
}

double TetPaint::GetCutoffRadius() const
{
  if (!(Width_ > 0.0) || !(Strength_ > 0.0) || CutoffWeight_ >= Strength_)
  {
    return 0.0;
  }
  if (!(CutoffWeight_ > 0.0))
  {
    return std::numeric_limits<double>::infinity();
  }
  // w(R) = Strength exp(-R^2 / (2 Width^2)) = CutoffWeight.
  return Width_ * std::sqrt(2.0 * std::log(Strength_ / CutoffWeight_));
}

namespace
{
/// Paint: the bounding box of the stroke points grown by `radius`.
void StrokeBox(const std::vector<double>& strokePoints, double radius, double boxLo[3],
  double boxHi[3])
{
  const double* stroke = strokePoints.data();
  const size_t numStroke = strokePoints.size() / 3;
  for (int a = 0; a < 3; ++a)
  {
    boxLo[a] = boxHi[a] = stroke[a];
    for (size_t s = 1; s < numStroke; ++s)
    {
      boxLo[a] = std::min(boxLo[a], stroke[3 * s + a]);
      boxHi[a] = std::max(boxHi[a], stroke[3 * s + a]);
    }
    boxLo[a] -= radius;
    boxHi[a] += radius;
  }
}

/// Paint: the blend of weight w toward the targets (TransCut Sec. 5.2: set,
/// multiply or add; modeIndex 0, 1, 2) of one cell's unmasked channels,
/// clamped at 0; a channel whose two values would both be 0 is kept (counted
/// in `kept`). Returns whether a value changed.
inline bool BlendCell(double w, double* const x[2], const double* const target[2],
  const bool mask[3], int modeIndex, long long& kept)
{
  bool modified = false;
  for (int c = 0; c < 3; ++c)
  {
    if (!mask[c])
    {
      continue;
    }
    double v[2];
    for (int k = 0; k < 2; ++k)
    {
      const double old = x[k][c];
      const double tk = target[k][c];
      switch (modeIndex)
      {
        case 0: // Set
          v[k] = (1.0 - w) * old + w * tk;
          break;
        case 1: // Multiply
          v[k] = old * (1.0 + w * (tk - 1.0));
          break;
        default: // Add
          v[k] = old + w * tk;
          break;
      }
      v[k] = v[k] > 0.0 ? v[k] : 0.0;
    }
    if (v[0] + v[1] > 0.0)
    {
      modified = modified || v[0] != x[0][c] || v[1] != x[1][c];
      x[0][c] = v[0];
      x[1][c] = v[1];
    }
    else
    {
      ++kept;
    }
  }
  return modified;
}

/// Paint: the error for cell `firstBad` (no points, or a point id out of
/// range).
template <typename IdT>
[[noreturn]] void ThrowBadCell(std::int64_t firstBad, const IdT* offsets, const IdT* connectivity,
  std::int64_t numberOfPoints)
{
  std::ostringstream os;
  os << "TetPaint: cell " << firstBad << " has ";
  const std::int64_t first = static_cast<std::int64_t>(offsets[firstBad]);
  const std::int64_t last = static_cast<std::int64_t>(offsets[firstBad + 1]);
  if (last <= first)
  {
    os << "no points";
  }
  else
  {
    os << "a point id out of range (the mesh has " << numberOfPoints << " points):";
    for (std::int64_t k = first; k < last; ++k)
    {
      os << ' ' << static_cast<std::int64_t>(connectivity[k]);
    }
  }
  throw Error(os.str());
}
} // namespace

template <typename PointT, typename IdT>
void TetPaint::Paint(const PointT* points, std::int64_t numberOfPoints, const IdT* offsets,
  const IdT* connectivity, std::int64_t numberOfCells, double* absorption, double* scattering,
  double* weights)
{
  Validate();
  Changed_.clear();
  Kept_ = 0;
  Candidates_ = 0;
  const std::int64_t n = numberOfCells;
  const double radius = GetCutoffRadius();
  const bool paints = radius > 0.0;
  const bool cutoff = std::isfinite(radius);
  const double radius2 = radius * radius;
  const double twoSigma2 = 2.0 * Width_ * Width_;
  const double strength = Strength_;
  const double* stroke = Stroke_.data();
  const size_t numStroke = Stroke_.size() / 3;

  StrokeGrid grid;
  double boxLo[3] = { 0, 0, 0 }, boxHi[3] = { 0, 0, 0 };
  if (paints && cutoff)
  {
    grid.Build(Stroke_, radius);
    StrokeBox(Stroke_, radius, boxLo, boxHi);
  }
  const int modeIndex = static_cast<int>(Mode_);
  const double* target[2] = { TargetAbsorption_.data(), TargetScattering_.data() };
  const bool mask[3] = { Mask_[0], Mask_[1], Mask_[2] };

  const int numThreads = NumberOfThreads_ > 0 ? NumberOfThreads_ : omp_get_max_threads();
  std::vector<std::vector<int>> changedPerThread(static_cast<size_t>(numThreads));
  std::int64_t firstBad = std::numeric_limits<std::int64_t>::max();
  long long kept = 0, candidates = 0;
#pragma omp parallel num_threads(numThreads) reduction(+ : kept, candidates) \
  reduction(min : firstBad)
  {
    // Static contiguous blocks in thread order: concatenating the threads'
    // lists gives the changed cells in ascending order for any thread count.
    const int thread = omp_get_thread_num();
    const int threads = omp_get_num_threads();
    const std::int64_t begin = n * thread / threads;
    const std::int64_t end = n * (thread + 1) / threads;
    std::vector<int>& changed = changedPerThread[static_cast<size_t>(thread)];
    for (std::int64_t t = begin; t < end; ++t)
    {
      double w = 0.0;
      const std::int64_t first = static_cast<std::int64_t>(offsets[t]);
      const std::int64_t last = static_cast<std::int64_t>(offsets[t + 1]);
      if (last <= first)
      {
        firstBad = std::min(firstBad, t);
        continue;
      }
      if (paints)
      {
        // Centroid: the mean of the cell's vertices.
        double c[3] = { 0.0, 0.0, 0.0 };
        const double npts = static_cast<double>(last - first);
        bool bad = false;
        for (std::int64_t k = first; k < last; ++k)
        {
          const std::int64_t id = static_cast<std::int64_t>(connectivity[k]);
          if (id < 0 || id >= numberOfPoints)
          {
            bad = true;
            break;
          }
          const PointT* x = points + 3 * id;
          for (int a = 0; a < 3; ++a)
          {
            c[a] += static_cast<double>(x[a]) / npts;
          }
        }
        if (bad)
        {
          firstBad = std::min(firstBad, t);
          continue;
        }
        double d2;
        if (cutoff)
        {
          // Written so that a NaN centroid (NaN points) is outside too.
          if (!(c[0] >= boxLo[0] && c[0] <= boxHi[0] && c[1] >= boxLo[1] && c[1] <= boxHi[1] &&
                c[2] >= boxLo[2] && c[2] <= boxHi[2]))
          {
            if (weights)
            {
              weights[t] = 0.0;
            }
            continue;
          }
          ++candidates;
          d2 = grid.NearestSquared(c, stroke);
        }
        else
        {
          ++candidates;
          d2 = std::numeric_limits<double>::infinity();
          for (size_t s = 0; s < numStroke; ++s)
          {
            const double* p = stroke + 3 * s;
            const double dx = c[0] - p[0], dy = c[1] - p[1], dz = c[2] - p[2];
            const double e = dx * dx + dy * dy + dz * dz;
            d2 = e < d2 ? e : d2;
          }
        }
        // TransCut Sec. 5.2: influence from the closest stroke point through a
        // Gaussian, cut off beyond R (documented in Documentation/Materials.md).
        w = (!cutoff || d2 <= radius2) ? strength * std::exp(-d2 / twoSigma2) : 0.0;
      }
      if (weights)
      {
        weights[t] = w;
      }
      if (!(w > 0.0))
      {
        continue;
      }
      double* x[2] = { absorption + 3 * t, scattering + 3 * t };
      if (BlendCell(w, x, target, mask, modeIndex, kept))
      {
        changed.push_back(static_cast<int>(t));
      }
    }
  }
  if (firstBad != std::numeric_limits<std::int64_t>::max())
  {
    ThrowBadCell(firstBad, offsets, connectivity, numberOfPoints);
  }
  size_t total = 0;
  for (const auto& list : changedPerThread)
  {
    total += list.size();
  }
  Changed_.reserve(total);
  for (const auto& list : changedPerThread)
  {
    Changed_.insert(Changed_.end(), list.begin(), list.end());
  }
  Kept_ = kept;
  Candidates_ = candidates;
}

void TetPaint::Paint(const std::vector<double>& points, const std::vector<int>& tets,
  std::vector<double>& absorption, std::vector<double>& scattering, std::vector<double>* weights)
{
  const std::int64_t numTets = static_cast<std::int64_t>(tets.size() / 4);
  if (tets.size() % 4 != 0 || absorption.size() != 3 * tets.size() / 4 ||
    scattering.size() != 3 * tets.size() / 4 || points.size() % 3 != 0)
  {
    std::ostringstream os;
    os << "TetPaint: " << tets.size() << " tet ids (4 per tet), " << absorption.size()
       << " absorption and " << scattering.size() << " scattering values (3 per tet), "
       << points.size() << " point coordinates (3 per point): inconsistent sizes";
    throw Error(os.str());
  }
  std::vector<int> offsets(static_cast<size_t>(numTets) + 1);
  for (std::int64_t t = 0; t <= numTets; ++t)
  {
    offsets[static_cast<size_t>(t)] = static_cast<int>(4 * t);
  }
  if (weights)
  {
    weights->resize(static_cast<size_t>(numTets));
  }
  Paint(points.data(), static_cast<std::int64_t>(points.size() / 3), offsets.data(), tets.data(),
    numTets, absorption.data(), scattering.data(), weights ? weights->data() : nullptr);
}

template void TetPaint::Paint<float, int>(const float*, std::int64_t,
  const int*, const int*, std::int64_t, double*, double*, double*);
template void TetPaint::Paint<float, long long>(const float*, std::int64_t,
  const long long*, const long long*, std::int64_t, double*, double*, double*);
template void TetPaint::Paint<double, int>(const double*, std::int64_t,
  const int*, const int*, std::int64_t, double*, double*, double*);
template void TetPaint::Paint<double, long long>(const double*, std::int64_t,
  const long long*, const long long*, std::int64_t, double*, double*, double*);

} // namespace translucency
