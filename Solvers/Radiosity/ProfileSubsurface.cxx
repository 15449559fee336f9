#include "ProfileSubsurface.h"

#include "Error.h"
#include "Fresnel.h"
#include "RadiosityScene.h"
#include "TetLocator.h"
#include "TetMesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <queue>
#include <sstream>
#include <tuple>

namespace translucency
{

namespace
{
constexpr double Pi = 3.14159265358979323846;
constexpr int MaxMaterials = 4;
/// Sub-triangles per side for the sampled (near) entries: K^2 = 100 samples
/// (paper Sec. 5.2: "the number of sampling points on the polygon itself is 100").
constexpr int SampleSide = 10;

struct Entry
{
  int Exit;  // j
  int Entry_; // i
  float Distance;
  unsigned char Near;
  std::array<float, MaxMaterials> Fractions;
};

/// The voxel grid of Setup (paper Sec. 5.2): voxels of size H over the
/// bounding box from Lo, the inside ones (centre in a tet) numbered.
struct VoxelGrid
{
  double Lo[3] = { 0.0, 0.0, 0.0 };
  double H = 0.0;
  int Dims[3] = { 1, 1, 1 };
  long long NumVoxels = 0;
  std::vector<int> VoxelIndex;    ///< per voxel: its inside number, or -1
  std::vector<int> InsideVoxel;   ///< per inside voxel: its voxel
  std::vector<int> VoxelMaterial; ///< per inside voxel: its material
};

/// The patches of one object on the voxel grid: the inside voxel of each
/// patch, the patches of each inside voxel and the voxels that have some.
struct PatchVoxels
{
  std::vector<std::vector<int>> VoxelPatches;
  std::vector<int> Sources;
};

/// Setup: the distinct coefficient sets (materials) of the object, the
/// material of each tet and one tet per material.
void FindMaterials(
  const RadiosityObject& obj, std::vector<int>& tetMaterial, std::vector<int>& materialTet)
{
  const TetMesh& mesh = *obj.Mesh;
  const OpticalProperties& mat = obj.Material;
  const int numTets = mesh.GetNumberOfTets();
  tetMaterial.assign(numTets, 0);
  std::map<std::array<double, 7>, int> materialIds;
  for (int t = 0; t < numTets; ++t)
  {
    std::array<double, 7> key;
    for (int c = 0; c < 3; ++c)
    {
      key[c] = mat.AbsorptionCoefficient[3 * t + c];
      key[3 + c] = mat.ReducedScatteringCoefficient[3 * t + c];
    }
    key[6] = mat.RefractiveIndex[t];
    auto it = materialIds.find(key);
    if (it == materialIds.end())
    {
      if (static_cast<int>(materialTet.size()) == MaxMaterials)
      {
        std::ostringstream os;
        os << "profile S: object '" << obj.Name << "' has more than " << MaxMaterials
           << " distinct materials (tet " << t
           << "); the eq. 16 heuristic is for a few homogeneous parts: use the diffusion S";
        throw Error(os.str());
      }
      it = materialIds.emplace(key, static_cast<int>(materialTet.size())).first;
      materialTet.push_back(t);
    }
    tetMaterial[t] = it->second;
  }
}

/// Setup: max_d where every material's profile has fallen below 1e-4 of its
/// value at r = h (capped at the bounding-box diagonal).
double ProfileCutOff(
  const OpticalProperties& mat, const std::vector<int>& materialTet, double h, double diagonal)
{
  double maxd = h;
  for (int m : materialTet)
  {
    for (int c = 0; c < 3; ++c)
    {
      const double a = mat.AbsorptionCoefficient[3 * m + c];
      const double s = mat.ReducedScatteringCoefficient[3 * m + c];
      const double eta = mat.RefractiveIndex[m];
      const double ref = DipoleProfile(h, a, s, eta);
      double r = h;
      while (r < diagonal && DipoleProfile(r, a, s, eta) > 1e-4 * ref)
      {
        r += 0.25 * h;
      }
      maxd = std::max(maxd, r);
    }
  }
  return std::min(maxd, diagonal);
}

/// Setup: the inside voxels (centre in a tet) and their material.
void FindInsideVoxels(const TetMesh& mesh, const std::vector<int>& tetMaterial, VoxelGrid& grid)
{
  const double* lo = grid.Lo;
  const double h = grid.H;
  const int* dims = grid.Dims;
  const long long numVoxels = grid.NumVoxels;
  std::vector<int>& voxelIndex = grid.VoxelIndex;
  std::vector<int>& insideVoxel = grid.InsideVoxel;
  std::vector<int>& voxelMaterial = grid.VoxelMaterial;
  voxelIndex.assign(numVoxels, -1);
  TetLocator locator;
  locator.Build(mesh);
  for (long long v = 0; v < numVoxels; ++v)
  {
    const int i = static_cast<int>(v % dims[0]);
    const int j = static_cast<int>((v / dims[0]) % dims[1]);
    const int k = static_cast<int>(v / (static_cast<long long>(dims[0]) * dims[1]));
    const double x[3] = { lo[0] + (i + 0.5) * h, lo[1] + (j + 0.5) * h, lo[2] + (k + 0.5) * h };
    const int tet = locator.Locate(x);
    if (tet >= 0)
    {
      voxelIndex[v] = static_cast<int>(insideVoxel.size());
      insideVoxel.push_back(static_cast<int>(v));
      voxelMaterial.push_back(tetMaterial[tet]);
    }
  }
}

/// Setup: patch -> nearest inside voxel of its centroid (looked up just
/// inside), then the patches of each voxel and the voxels with patches.
PatchVoxels MatchPatchVoxels(const RadiosityScene& scene, int object, const VoxelGrid& grid)
{
  const RadiosityObject& obj = scene.GetObject(object);
  const TetMesh& mesh = *obj.Mesh;
  const double* lo = grid.Lo;
  const double h = grid.H;
  const int* dims = grid.Dims;
  const std::vector<int>& voxelIndex = grid.VoxelIndex;
  const int numInside = static_cast<int>(grid.InsideVoxel.size());
  const int begin = scene.GetPatchOffset(object);
  const int numPatches = mesh.GetNumberOfBoundaryTriangles();
  const std::vector<double>& centroids = scene.GetCentroids();
  const std::vector<double>& normals = scene.GetNormals();
  std::vector<int> patchVoxel(numPatches, -1);
  for (int p = 0; p < numPatches; ++p)
  {
    const double* c = &centroids[3 * static_cast<size_t>(begin + p)];
    const double* n = &normals[3 * static_cast<size_t>(begin + p)];
    int cell[3];
    for (int d = 0; d < 3; ++d)
    {
      cell[d] = std::min(dims[d] - 1,
        std::max(0, static_cast<int>(std::floor((c[d] - 0.25 * h * n[d] - lo[d]) / h))));
    }
    double best = std::numeric_limits<double>::infinity();
    for (int radius = 0; radius <= 3 && patchVoxel[p] < 0; ++radius)
    {
      for (int dk = -radius; dk <= radius; ++dk)
        for (int dj = -radius; dj <= radius; ++dj)
          for (int di = -radius; di <= radius; ++di)
          {
            const int ii = cell[0] + di, jj = cell[1] + dj, kk = cell[2] + dk;
            if (ii < 0 || jj < 0 || kk < 0 || ii >= dims[0] || jj >= dims[1] || kk >= dims[2])
              continue;
            const long long v = ii + static_cast<long long>(dims[0]) * (jj + static_cast<long long>(dims[1]) * kk);
            if (voxelIndex[v] < 0)
              continue;
            const double x[3] = { lo[0] + (ii + 0.5) * h, lo[1] + (jj + 0.5) * h,
              lo[2] + (kk + 0.5) * h };
            const double d2 = (x[0] - c[0]) * (x[0] - c[0]) + (x[1] - c[1]) * (x[1] - c[1]) +
              (x[2] - c[2]) * (x[2] - c[2]);
            if (d2 < best)
            {
              best = d2;
              patchVoxel[p] = voxelIndex[v];
            }
          }
    }
    if (patchVoxel[p] < 0)
    {
      std::ostringstream os;
      os << "profile S: object '" << obj.Name << "', patch " << p
         << ": no inside voxel within 3 voxels of its centroid (voxel size " << h
         << " mm is too coarse for this object)";
      throw Error(os.str());
    }
  }
  PatchVoxels out;
  std::vector<std::vector<int>>& voxelPatches = out.VoxelPatches;
  std::vector<int>& sources = out.Sources;
  voxelPatches.resize(numInside);
  for (int p = 0; p < numPatches; ++p)
  {
    voxelPatches[patchVoxel[p]].push_back(p);
  }
  for (int v = 0; v < numInside; ++v)
  {
    if (!voxelPatches[v].empty())
    {
      sources.push_back(v);
    }
  }

  return out;
}

/// Setup: Dijkstra from every source voxel, cut off at max_d (paper Sec.
/// 5.2): the entries S_ji (exit patch j, entry patch i) with their distance
/// and the material fractions along the path, per source.
std::vector<std::vector<Entry>> ShortestPathEntries(const RadiosityScene& scene, int object,
  const VoxelGrid& grid, const PatchVoxels& patches, int nm, double maxd)
{
  const TetMesh& mesh = *scene.GetObject(object).Mesh;
  const int begin = scene.GetPatchOffset(object);
  const std::vector<double>& centroids = scene.GetCentroids();
  const double h = grid.H;
  const int* dims = grid.Dims;
  const std::vector<int>& voxelIndex = grid.VoxelIndex;
  const std::vector<int>& insideVoxel = grid.InsideVoxel;
  const std::vector<int>& voxelMaterial = grid.VoxelMaterial;
  const std::vector<std::vector<int>>& voxelPatches = patches.VoxelPatches;
  const std::vector<int>& sources = patches.Sources;
  const int numInside = static_cast<int>(insideVoxel.size());
  std::vector<std::vector<Entry>> perSource(sources.size());
#pragma omp parallel
  {
    std::vector<double> dist(numInside, std::numeric_limits<double>::infinity());
    std::vector<std::array<float, MaxMaterials>> lengths(nm > 1 ? numInside : 0);
    std::vector<int> touched;
#pragma omp for schedule(dynamic, 4)
    for (int s = 0; s < static_cast<int>(sources.size()); ++s)
    {
      const int src = sources[s];
      using Item = std::pair<double, int>;
      std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
      dist[src] = 0.0;
      touched.push_back(src);
      if (nm > 1)
      {
        lengths[src].fill(0.0f);
      }
      heap.push({ 0.0, src });
      std::vector<std::pair<int, double>> settled;
      while (!heap.empty())
      {
        const auto [du, u] = heap.top();
        heap.pop();
        if (du > dist[u])
        {
          continue;
        }
        settled.emplace_back(u, du);
        const long long vu = insideVoxel[u];
        const int ui = static_cast<int>(vu % dims[0]);
        const int uj = static_cast<int>((vu / dims[0]) % dims[1]);
        const int uk = static_cast<int>(vu / (static_cast<long long>(dims[0]) * dims[1]));
        for (int dk = -1; dk <= 1; ++dk)
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di)
            {
              if (!di && !dj && !dk)
                continue;
              const int ii = ui + di, jj = uj + dj, kk = uk + dk;
              if (ii < 0 || jj < 0 || kk < 0 || ii >= dims[0] || jj >= dims[1] || kk >= dims[2])
                continue;
              const int w = voxelIndex[ii + static_cast<long long>(dims[0]) *
                (jj + static_cast<long long>(dims[1]) * kk)];
              if (w < 0)
                continue;
              const double step = h * std::sqrt(static_cast<double>(di * di + dj * dj + dk * dk));
              const double dw = du + step;
              // Stop at max_d (paper Sec. 5.2): farther voxels are never settled.
              if (dw > maxd || dw >= dist[w])
                continue;
              if (dist[w] == std::numeric_limits<double>::infinity())
                touched.push_back(w);
              dist[w] = dw;
              if (nm > 1)
              {
                lengths[w] = lengths[u];
                lengths[w][voxelMaterial[u]] += static_cast<float>(0.5 * step);
                lengths[w][voxelMaterial[w]] += static_cast<float>(0.5 * step);
              }
              heap.push({ dw, w });
            }
      }
      // Entries S_ji for entry patches i at src and exit patches j at settled voxels.
      auto& out = perSource[s];
      for (const auto& [v, dv] : settled)
      {
        std::array<float, MaxMaterials> fractions{};
        if (nm > 1)
        {
          float total = 0.0f;
          for (int m = 0; m < nm; ++m)
            total += lengths[v][m];
          for (int m = 0; m < nm; ++m)
            fractions[m] = total > 0.0f ? lengths[v][m] / total : 0.0f;
          if (total == 0.0f)
            fractions[voxelMaterial[v]] = 1.0f;
        }
        else
        {
          fractions[0] = 1.0f;
        }
        for (int i : voxelPatches[src])
        {
          const double* ci = &centroids[3 * static_cast<size_t>(begin + i)];
          for (int j : voxelPatches[v])
          {
            const double* cj = &centroids[3 * static_cast<size_t>(begin + j)];
            const double e = std::sqrt((ci[0] - cj[0]) * (ci[0] - cj[0]) +
              (ci[1] - cj[1]) * (ci[1] - cj[1]) + (ci[2] - cj[2]) * (ci[2] - cj[2]));
            const double r = v == src ? e : std::max(dv, e);
            if (r > maxd)
              continue;
            Entry entry;
            entry.Exit = j;
            entry.Entry_ = i;
            entry.Distance = static_cast<float>(r);
            entry.Near = e < 3.0 * std::sqrt(mesh.GetBoundaryTriangleAreas()[i]) ? 1 : 0;
            entry.Fractions = fractions;
            out.push_back(entry);
          }
        }
      }
      for (int t : touched)
        dist[t] = std::numeric_limits<double>::infinity();
      touched.clear();
    }
  }
  return perSource;
}

} // namespace

double DipoleProfile(double r, double muA, double sigmaS, double eta)
{
  // Jensen et al. 2001, dipole diffuse reflectance R_d(r).
  const double sigmaT = muA + sigmaS;
  const double alpha = sigmaS / sigmaT;
  const double sigmaTr = std::sqrt(3.0 * muA * sigmaT);
  const double a = Fresnel::MismatchA(eta);
  const double zr = 1.0 / sigmaT;
  const double zv = zr * (1.0 + 4.0 * a / 3.0);
  const double dr = std::sqrt(r * r + zr * zr);
  const double dv = std::sqrt(r * r + zv * zv);
  return alpha / (4.0 * Pi) *
    (zr * (sigmaTr * dr + 1.0) * std::exp(-sigmaTr * dr) / (dr * dr * dr) +
      zv * (sigmaTr * dv + 1.0) * std::exp(-sigmaTr * dv) / (dv * dv * dv));
}

void ProfileSubsurface::Setup(const RadiosityScene& scene, int object)
{
  const RadiosityObject& obj = scene.GetObject(object);
  if (!obj.Translucent || !obj.Mesh)
  {
    throw Error("profile S: object " + std::to_string(object) + " is not translucent");
  }
  const TetMesh& mesh = *obj.Mesh;
  const OpticalProperties& mat = obj.Material;
  std::vector<int> tetMaterial, materialTet;
  FindMaterials(obj, tetMaterial, materialTet);
  // Same mesh and the same material layout: reuse the distances (paper
  // Sec. 4: "by simply recomputing the 1-D profiles, we can vary the
  // translucency"); only the profile values change.
  if (Mesh_ == &mesh && tetMaterial == TetMaterial_ && !RowOffsets_.empty())
  {
    MaterialTet_ = materialTet;
    Evaluate(scene, object);
    return;
  }
  Mesh_ = &mesh;
  TetMaterial_ = tetMaterial;
  MaterialTet_ = materialTet;
  NumberOfMaterials_ = static_cast<int>(materialTet.size());

  // Voxel grid over the bounding box.
  VoxelGrid grid;
  double* lo = grid.Lo;
  double hi[3];
  for (int d = 0; d < 3; ++d)
  {
    lo[d] = std::numeric_limits<double>::infinity();
    hi[d] = -lo[d];
  }
  for (int i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    for (int d = 0; d < 3; ++d)
    {
      lo[d] = std::min(lo[d], mesh.GetPoint(i)[d]);
      hi[d] = std::max(hi[d], mesh.GetPoint(i)[d]);
    }
  }
  const double largest = std::max({ hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2] });
  const double diagonal = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) +
    (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
  if (!(VoxelSize_ >= 0.0) || !(MaxDistance_ >= 0.0))
  {
    throw Error("profile S: the voxel size and max_d must be >= 0 (0 = automatic)");
  }
  const double h = VoxelSize_ > 0.0 ? VoxelSize_ : largest / 32.0;
  UsedVoxelSize_ = h;
  grid.H = h;
  int* dims = grid.Dims;
  for (int d = 0; d < 3; ++d)
  {
    dims[d] = std::max(1, static_cast<int>(std::ceil((hi[d] - lo[d]) / h)));
  }
  const long long numVoxels = static_cast<long long>(dims[0]) * dims[1] * dims[2];
  if (numVoxels > 20000000LL)
  {
    std::ostringstream os;
    os << "profile S: voxel size " << h << " mm gives " << numVoxels
       << " voxels (limit 2e7): choose a larger voxel size";
    throw Error(os.str());
  }
  // max_d: where every profile has fallen below 1e-4 of its value at r = h.
  if (MaxDistance_ > 0.0)
  {
    UsedMaxDistance_ = MaxDistance_;
  }
  else
  {
    UsedMaxDistance_ = ProfileCutOff(mat, materialTet, h, diagonal);
  }
  const double maxd = UsedMaxDistance_;

  grid.NumVoxels = numVoxels;
  FindInsideVoxels(mesh, tetMaterial, grid);
  NumberOfInside_ = static_cast<int>(grid.InsideVoxel.size());
  const PatchVoxels patches = MatchPatchVoxels(scene, object, grid);
  const int numPatches = mesh.GetNumberOfBoundaryTriangles();
  const int nm = NumberOfMaterials_;
  std::vector<std::vector<Entry>> perSource =
    ShortestPathEntries(scene, object, grid, patches, nm, maxd);

  // CSR by exit patch.
  std::vector<Entry> all;
  for (auto& v : perSource)
  {
    all.insert(all.end(), v.begin(), v.end());
    std::vector<Entry>().swap(v);
  }
  std::sort(all.begin(), all.end(), [](const Entry& a, const Entry& b) {
    return std::tie(a.Exit, a.Entry_) < std::tie(b.Exit, b.Entry_);
  });
  RowOffsets_.assign(numPatches + 1, 0);
  Columns_.resize(all.size());
  Distances_.resize(all.size());
  Near_.resize(all.size());
  Fractions_.assign(nm > 1 ? all.size() * nm : 0, 0.0f);
  for (size_t e = 0; e < all.size(); ++e)
  {
    ++RowOffsets_[all[e].Exit + 1];
    Columns_[e] = all[e].Entry_;
    Distances_[e] = all[e].Distance;
    Near_[e] = all[e].Near;
    if (nm > 1)
    {
      std::copy(all[e].Fractions.begin(), all[e].Fractions.begin() + nm, &Fractions_[e * nm]);
    }
  }
  for (int j = 0; j < numPatches; ++j)
  {
    RowOffsets_[j + 1] += RowOffsets_[j];
  }
  Evaluate(scene, object);
}

void ProfileSubsurface::Evaluate(const RadiosityScene& scene, int object)
{
  const RadiosityObject& obj = scene.GetObject(object);
  const TetMesh& mesh = *obj.Mesh;
  const OpticalProperties& mat = obj.Material;
  const int nm = NumberOfMaterials_;
  const int begin = scene.GetPatchOffset(object);
  const int numPatches = mesh.GetNumberOfBoundaryTriangles();
  const std::vector<double>& centroids = scene.GetCentroids();
  const std::vector<double>& points = mesh.GetPoints();
  const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
  const std::vector<double>& areas = mesh.GetBoundaryTriangleAreas();
  // Profile of the path: eq. 16 over the materials crossed (one material: R(r)).
  double r0[MaxMaterials][3];
  for (int m = 0; m < nm; ++m)
  {
    const int t = MaterialTet_[m];
    for (int c = 0; c < 3; ++c)
    {
      r0[m][c] = DipoleProfile(0.0, mat.AbsorptionCoefficient[3 * t + c],
        mat.ReducedScatteringCoefficient[3 * t + c], mat.RefractiveIndex[t]);
    }
  }
  auto profile = [&](double r, const float* fractions, double out[3]) {
    if (nm == 1)
    {
      const int t = MaterialTet_[0];
      for (int c = 0; c < 3; ++c)
        out[c] = DipoleProfile(r, mat.AbsorptionCoefficient[3 * t + c],
          mat.ReducedScatteringCoefficient[3 * t + c], mat.RefractiveIndex[t]);
      return;
    }
    for (int c = 0; c < 3; ++c)
    {
      // Paper eq. 16, N materials: (sum_m S_m(0) r_m / r) prod_m S_m(r_m) / S_m(0).
      double mix = 0.0, product = 1.0;
      for (int m = 0; m < nm; ++m)
      {
        if (fractions[m] <= 0.0f)
          continue;
        const int t = MaterialTet_[m];
        mix += r0[m][c] * fractions[m];
        product *= DipoleProfile(fractions[m] * r, mat.AbsorptionCoefficient[3 * t + c],
                     mat.ReducedScatteringCoefficient[3 * t + c], mat.RefractiveIndex[t]) /
          r0[m][c];
      }
      out[c] = mix * product;
    }
  };
  Values_.assign(3 * Columns_.size(), 0.0);
#pragma omp parallel for schedule(dynamic, 16)
  for (int j = 0; j < numPatches; ++j)
  {
    const double* cj = &centroids[3 * static_cast<size_t>(begin + j)];
    // R_d is already the exitance (the flux leaving through the boundary
    // condition with A): no further Fresnel factor for a radiosity.
    const double tu = 1.0;
    for (int e = RowOffsets_[j]; e < RowOffsets_[j + 1]; ++e)
    {
      const int i = Columns_[e];
      const float* fr = nm > 1 ? &Fractions_[static_cast<size_t>(e) * nm] : nullptr;
      double value[3] = { 0.0, 0.0, 0.0 };
      if (Near_[e])
      {
        // Paper eq. 8 with the exit point at the centroid: 100 samples of patch i.
        const double* a = &points[3 * static_cast<size_t>(triangles[3 * i])];
        const double* b = &points[3 * static_cast<size_t>(triangles[3 * i + 1])];
        const double* c = &points[3 * static_cast<size_t>(triangles[3 * i + 2])];
        const double w = areas[i] / (SampleSide * SampleSide);
        for (int u = 0; u < SampleSide; ++u)
        {
          for (int v = 0; u + v < SampleSide; ++v)
          {
            for (int up = 0; up < 2; ++up)
            {
              if (up == 1 && u + v > SampleSide - 2)
                continue;
              const double bu = (u + (up ? 2.0 : 1.0) / 3.0) / SampleSide;
              const double bv = (v + (up ? 2.0 : 1.0) / 3.0) / SampleSide;
              double x[3];
              for (int d = 0; d < 3; ++d)
                x[d] = a[d] + bu * (b[d] - a[d]) + bv * (c[d] - a[d]);
              const double r = std::sqrt((x[0] - cj[0]) * (x[0] - cj[0]) +
                (x[1] - cj[1]) * (x[1] - cj[1]) + (x[2] - cj[2]) * (x[2] - cj[2]));
              double p[3];
              profile(r, fr, p);
              for (int ch = 0; ch < 3; ++ch)
                value[ch] += w * p[ch];
            }
          }
        }
      }
      else
      {
        double p[3];
        profile(Distances_[e], fr, p);
        for (int ch = 0; ch < 3; ++ch)
          value[ch] = areas[i] * p[ch];
      }
      for (int ch = 0; ch < 3; ++ch)
        Values_[3 * static_cast<size_t>(e) + ch] = tu * value[ch];
    }
  }
}

void ProfileSubsurface::Apply(const std::vector<double>& q, std::vector<double>& radiosity)
{
  const int numPatches = static_cast<int>(RowOffsets_.size()) - 1;
  if (numPatches < 0 || q.size() != 3 * static_cast<size_t>(numPatches))
  {
    throw Error("profile S: Apply() before Setup() or wrong vector size");
  }
  radiosity.assign(q.size(), 0.0);
#pragma omp parallel for schedule(static, 64) if (numPatches > 16384)
  for (int j = 0; j < numPatches; ++j)
  {
    double s[3] = { 0.0, 0.0, 0.0 };
    for (int e = RowOffsets_[j]; e < RowOffsets_[j + 1]; ++e)
    {
      const double* qi = &q[3 * static_cast<size_t>(Columns_[e])];
      const double* v = &Values_[3 * static_cast<size_t>(e)];
      s[0] += v[0] * qi[0];
      s[1] += v[1] * qi[1];
      s[2] += v[2] * qi[2];
    }
    for (int c = 0; c < 3; ++c)
      radiosity[3 * static_cast<size_t>(j) + c] = s[c];
  }
}

std::size_t ProfileSubsurface::GetMemoryBytes() const
{
  return RowOffsets_.size() * sizeof(int) + Columns_.size() * sizeof(int) +
    Distances_.size() * sizeof(float) + Near_.size() + Fractions_.size() * sizeof(float) +
    Values_.size() * sizeof(double) + TetMaterial_.size() * sizeof(int);
}

} // namespace translucency
