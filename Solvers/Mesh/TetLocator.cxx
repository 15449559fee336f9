#include "TetLocator.h"

#include "TetMesh.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace translucency
{

namespace
{
/// At most this many bins (64 MiB of offsets).
constexpr double MaxBins = 16777216.0;
}

void TetLocator::Build(const TetMesh& mesh)
{
  Mesh_ = &mesh;
  BinOffsets_.clear();
  BinTets_.clear();
  Dims_[0] = Dims_[1] = Dims_[2] = 0;
  const int numTets = mesh.GetNumberOfTets();
  if (numTets == 0)
  {
    return;
  }
  const std::vector<int>& tets = mesh.GetTets();
  for (int d = 0; d < 3; ++d)
  {
    Bounds_[d] = std::numeric_limits<double>::infinity();
    Bounds_[d + 3] = -std::numeric_limits<double>::infinity();
  }
  for (int id : tets)
  {
    const double* p = mesh.GetPoint(id);
    for (int d = 0; d < 3; ++d)
    {
      Bounds_[d] = std::min(Bounds_[d], p[d]);
      Bounds_[d + 3] = std::max(Bounds_[d + 3], p[d]);
    }
  }
  // About one bin per tet: cubic bins of side s with volume / s^3 ~ tets.
  double extent[3], volume = 1.0, diagonal = 0.0;
  for (int d = 0; d < 3; ++d)
  {
    extent[d] = Bounds_[d + 3] - Bounds_[d];
    diagonal += extent[d] * extent[d];
  }
  diagonal = std::sqrt(diagonal);
  const double floorExtent = 1e-9 * diagonal; // flat boxes cannot happen, but be safe
  for (int d = 0; d < 3; ++d)
  {
    extent[d] = std::max(extent[d], floorExtent);
    volume *= extent[d];
  }
  double side = std::cbrt(volume / std::min<double>(numTets, MaxBins));
  for (;;)
  {
    double bins = 1.0;
    for (int d = 0; d < 3; ++d)
    {
      bins *= std::max(1.0, std::ceil(extent[d] / side));
    }
    if (bins <= MaxBins)
    {
      break;
    }
    side *= 1.1;
  }
  for (int d = 0; d < 3; ++d)
  {
    Dims_[d] = static_cast<int>(std::max(1.0, std::ceil(extent[d] / side)));
    BinSize_[d] = extent[d] / Dims_[d];
  }
  const double pad = 1e-9 * diagonal;
  auto binRange = [&](int t, int lo[3], int hi[3])
  {
    double bmin[3], bmax[3];
    for (int d = 0; d < 3; ++d)
    {
      bmin[d] = std::numeric_limits<double>::infinity();
      bmax[d] = -std::numeric_limits<double>::infinity();
    }
    const int* tv = mesh.GetTet(t);
    for (int a = 0; a < 4; ++a)
    {
      const double* p = mesh.GetPoint(tv[a]);
      for (int d = 0; d < 3; ++d)
      {
        bmin[d] = std::min(bmin[d], p[d]);
        bmax[d] = std::max(bmax[d], p[d]);
      }
    }
    for (int d = 0; d < 3; ++d)
    {
      lo[d] = std::clamp(
        static_cast<int>(std::floor((bmin[d] - pad - Bounds_[d]) / BinSize_[d])), 0, Dims_[d] - 1);
      hi[d] = std::clamp(
        static_cast<int>(std::floor((bmax[d] + pad - Bounds_[d]) / BinSize_[d])), 0, Dims_[d] - 1);
    }
  };
  const long long numBins = static_cast<long long>(Dims_[0]) * Dims_[1] * Dims_[2];
  BinOffsets_.assign(static_cast<size_t>(numBins) + 1, 0);
  int lo[3], hi[3];
  for (int t = 0; t < numTets; ++t)
  {
    binRange(t, lo, hi);
    for (int k = lo[2]; k <= hi[2]; ++k)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int i = lo[0]; i <= hi[0]; ++i)
          ++BinOffsets_[1 + i +
            static_cast<size_t>(Dims_[0]) * (j + static_cast<size_t>(Dims_[1]) * k)];
  }
  for (long long b = 0; b < numBins; ++b)
  {
    BinOffsets_[b + 1] += BinOffsets_[b];
  }
  BinTets_.resize(static_cast<size_t>(BinOffsets_.back()));
  std::vector<int> fill(BinOffsets_.begin(), BinOffsets_.end() - 1);
  // Tets in increasing id order: every bin's list is sorted.
  for (int t = 0; t < numTets; ++t)
  {
    binRange(t, lo, hi);
    for (int k = lo[2]; k <= hi[2]; ++k)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int i = lo[0]; i <= hi[0]; ++i)
          BinTets_[fill[i +
            static_cast<size_t>(Dims_[0]) * (j + static_cast<size_t>(Dims_[1]) * k)]++] = t;
  }
}

bool TetLocator::Barycentric(int t, const double x[3], double lambda[4]) const
{
  const int* tv = Mesh_->GetTet(t);
  const double* p0 = Mesh_->GetPoint(tv[0]);
  const double* p1 = Mesh_->GetPoint(tv[1]);
  const double* p2 = Mesh_->GetPoint(tv[2]);
  const double* p3 = Mesh_->GetPoint(tv[3]);
  const double e1[3] = { p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2] };
  const double e2[3] = { p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2] };
  const double e3[3] = { p3[0] - p0[0], p3[1] - p0[1], p3[2] - p0[2] };
  const double r[3] = { x[0] - p0[0], x[1] - p0[1], x[2] - p0[2] };
  auto triple = [](const double* a, const double* b, const double* c)
  {
    return a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) +
      a[2] * (b[0] * c[1] - b[1] * c[0]);
  };
  const double det = triple(e1, e2, e3);
  if (!(det != 0.0) || !std::isfinite(det))
  {
    return false;
  }
  // Cramer's rule for r = l1 e1 + l2 e2 + l3 e3.
  lambda[1] = triple(r, e2, e3) / det;
  lambda[2] = triple(e1, r, e3) / det;
  lambda[3] = triple(e1, e2, r) / det;
  lambda[0] = 1.0 - lambda[1] - lambda[2] - lambda[3];
  return true;
}

int TetLocator::Locate(const double x[3]) const
{
  if (!Mesh_ || BinOffsets_.empty())
  {
    return -1;
  }
  int bin[3];
  for (int d = 0; d < 3; ++d)
  {
    const double u = (x[d] - Bounds_[d]) / BinSize_[d];
    if (!(u >= -1e-6 && u <= Dims_[d] + 1e-6))
    {
      return -1; // outside the box (or NaN)
    }
    bin[d] = std::clamp(static_cast<int>(std::floor(u)), 0, Dims_[d] - 1);
  }
  const size_t b =
    bin[0] + static_cast<size_t>(Dims_[0]) * (bin[1] + static_cast<size_t>(Dims_[1]) * bin[2]);
  double lambda[4];
  for (int k = BinOffsets_[b]; k < BinOffsets_[b + 1]; ++k)
  {
    const int t = BinTets_[k];
    if (Barycentric(t, x, lambda) && lambda[0] >= -Tolerance_ && lambda[1] >= -Tolerance_ &&
      lambda[2] >= -Tolerance_ && lambda[3] >= -Tolerance_)
    {
      return t;
    }
  }
  return -1;
}

} // namespace translucency
