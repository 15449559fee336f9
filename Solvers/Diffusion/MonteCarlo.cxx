#include "MonteCarlo.h"

#include "Error.h"
#include "Fresnel.h"
#include "InteriorSources.h"
#include "LightSources.h"
#include "Radiance.h"
#include "RayCaster.h"
#include "ResourceLimits.h"
#include "TetMesh.h"
#include "Timer.h"
#include "TriangleGeometry.h"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <sstream>

namespace translucency
{

namespace
{

constexpr double Pi = 3.14159265358979323846;

/// Launch weight fraction below which Russian roulette is played, and the
/// survival probability (survivors are multiplied by its inverse).
constexpr double RouletteThreshold = 1e-4;
constexpr double RouletteSurvival = 0.1;
/// Safety limits of one photon: consecutive zero-length segments (a photon
/// stuck on an edge by rounding) and segments in all (a photon trapped by
/// total internal reflection in a non-scattering, non-absorbing region).
constexpr int MaxZeroSteps = 1000;
constexpr long long MaxSteps = 10000000;
/// Photons between two abort checks / progress reports.
constexpr long long Chunk = 256;

/// SplitMix64 finaliser: a bijective 64-bit mix.
inline std::uint64_t Mix64(std::uint64_t z)
{
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

/**
 * xoshiro256** (Blackman and Vigna), one stream per photon: the state is
 * filled by SplitMix64 from a key that hashes (seed, channel, photon index),
 * so a photon's random numbers do not depend on which thread or batch traces
 * it.
 */
class PhotonRandom
{
public:
  PhotonRandom(std::uint64_t seed, int channel, long long photon)
  {
    std::uint64_t key = Mix64(Mix64(seed + 0x9E3779B97F4A7C15ULL) ^
      ((static_cast<std::uint64_t>(photon) << 2) | static_cast<std::uint64_t>(channel)));
    for (auto& s : S_)
    {
      key += 0x9E3779B97F4A7C15ULL;
      s = Mix64(key);
    }
  }

  std::uint64_t Next()
  {
    const std::uint64_t result = Rotl(S_[1] * 5, 7) * 9;
    const std::uint64_t t = S_[1] << 17;
    S_[2] ^= S_[0];
    S_[3] ^= S_[1];
    S_[1] ^= S_[2];
    S_[0] ^= S_[3];
    S_[2] ^= t;
    S_[3] = Rotl(S_[3], 45);
    return result;
  }
  /// Uniform in [0, 1).
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }
  /// Uniform in (0, 1) (safe for log).
  double OpenUniform() { return (static_cast<double>(Next() >> 11) + 0.5) * 0x1.0p-53; }

private:
  static std::uint64_t Rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::uint64_t S_[4];
};

inline double Dot(const double* a, const double* b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

inline void Normalize(double* a)
{
  const double len = std::sqrt(Dot(a, a));
  a[0] /= len;
  a[1] /= len;
  a[2] /= len;
}

/// Everything a step reads of a tet, in one place (2.5 cache lines):
/// barycentric planes lambda_f(x) = G[f] . x + E[f] (the barycentric
/// coordinate of vertex f: 0 on the face opposite f, local face f, and 1 at
/// vertex f; G[f] points from face f into the tet), the neighbours and the
/// coefficients of the channel being traced.
struct TetCell
{
  double G[4][3];
  double E[4];
  double MuS = 0.0; ///< scattering coefficient sigma_s' / (1 - g) (1/mm)
  double MuA = 0.0; ///< absorption coefficient (1/mm)
  /// Per local face: 4 * neighbour + neighbour's local face across it, or
  /// -1 - (boundary triangle index) on the boundary.
  int Next[4];
};

/// What the walk needs of the mesh.
struct WalkMesh
{
  std::vector<TetCell> Cells;
  /// Next of every tet, as a flat array while building.
  std::vector<int> Next;
  /// Per boundary triangle: 4 * owner tet + local face.
  std::vector<int> TriangleFace;

  std::size_t Bytes() const
  {
    return Cells.size() * sizeof(TetCell) + TriangleFace.size() * sizeof(int);
  }

  void Build(const TetMesh& mesh)
  {
    BuildCells(mesh);
    BuildAdjacency(mesh);
  }

  /// Build, 1. Per tet the barycentric gradients G_f and offsets E_f
  /// (lambda_f(x) = G_f . x + E_f).
  void BuildCells(const TetMesh& mesh)
  {
    const int numTets = mesh.GetNumberOfTets();
    Cells.resize(numTets);
#pragma omp parallel for schedule(static)
    for (int t = 0; t < numTets; ++t)
    {
      const int* v = mesh.GetTet(t);
      const double* p0 = mesh.GetPoint(v[0]);
      double j[3][3]; // columns p1 - p0, p2 - p0, p3 - p0
      for (int a = 0; a < 3; ++a)
      {
        const double* p = mesh.GetPoint(v[a + 1]);
        for (int k = 0; k < 3; ++k)
        {
          j[k][a] = p[k] - p0[k];
        }
      }
      // Rows of J^-1 = gradients of lambda_1..3 (adjugate / determinant).
      const double det = j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1]) -
        j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0]) +
        j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0]);
      TetCell& pl = Cells[t];
      for (int a = 0; a < 3; ++a)
      {
        const int a1 = (a + 1) % 3, a2 = (a + 2) % 3;
        // Row a of the inverse: cross product of columns a1 and a2 / det.
        pl.G[a + 1][0] = (j[1][a1] * j[2][a2] - j[2][a1] * j[1][a2]) / det;
        pl.G[a + 1][1] = (j[2][a1] * j[0][a2] - j[0][a1] * j[2][a2]) / det;
        pl.G[a + 1][2] = (j[0][a1] * j[1][a2] - j[1][a1] * j[0][a2]) / det;
      }
      for (int k = 0; k < 3; ++k)
      {
        pl.G[0][k] = -(pl.G[1][k] + pl.G[2][k] + pl.G[3][k]);
      }
      for (int f = 0; f < 4; ++f)
      {
        // lambda_f vanishes on the three other vertices: E from their mean.
        double sum = 0.0;
        for (int a = 0; a < 4; ++a)
        {
          if (a != f)
          {
            sum += Dot(pl.G[f], mesh.GetPoint(v[a]));
          }
        }
        pl.E[f] = -sum / 3.0;
      }
    }
  }

  /// Build, 2. Face adjacency (Next of each cell face: the neighbour's face
  /// code 4 t + f, or -1 - k for boundary triangle k), faces bucketed by
  /// their smallest vertex, matched by the other two inside each bucket.
  void BuildAdjacency(const TetMesh& mesh)
  {
    const int numTets = mesh.GetNumberOfTets();
    const int numPoints = mesh.GetNumberOfPoints();
    struct Face
    {
      int B, C, Code;
    };
    std::vector<int> offsets(static_cast<std::size_t>(numPoints) + 1, 0);
    auto key = [&](int t, int f, int& a, int& b, int& c) {
      const int* v = mesh.GetTet(t);
      int w[3], n = 0;
      for (int k = 0; k < 4; ++k)
      {
        if (k != f)
        {
          w[n++] = v[k];
        }
      }
      std::sort(w, w + 3);
      a = w[0];
      b = w[1];
      c = w[2];
    };
    for (int t = 0; t < numTets; ++t)
    {
      for (int f = 0; f < 4; ++f)
      {
        int a, b, c;
        key(t, f, a, b, c);
        ++offsets[a + 1];
      }
    }
    for (int i = 0; i < numPoints; ++i)
    {
      offsets[i + 1] += offsets[i];
    }
    std::vector<Face> faces(offsets.back());
    std::vector<int> fill(offsets.begin(), offsets.end() - 1);
    for (int t = 0; t < numTets; ++t)
    {
      for (int f = 0; f < 4; ++f)
      {
        int a, b, c;
        key(t, f, a, b, c);
        faces[fill[a]++] = Face{ b, c, 4 * t + f };
      }
    }
    const int unset = std::numeric_limits<int>::min();
    Next.assign(4 * static_cast<std::size_t>(numTets), unset);
    for (int i = 0; i < numPoints; ++i)
    {
      auto first = faces.begin() + offsets[i], last = faces.begin() + offsets[i + 1];
      std::sort(first, last, [](const Face& x, const Face& y) {
        return x.B != y.B ? x.B < y.B : (x.C != y.C ? x.C < y.C : x.Code < y.Code);
      });
      for (auto it = first; it != last;)
      {
        auto next = it + 1;
        if (next != last && next->B == it->B && next->C == it->C)
        {
          Next[it->Code] = next->Code;
          Next[next->Code] = it->Code;
          it += 2; // TetMesh rejects faces shared by more than two tets
        }
        else
        {
          ++it;
        }
      }
    }
    const std::vector<int>& triangles = mesh.GetBoundaryTriangles();
    const std::vector<int>& owners = mesh.GetBoundaryTriangleTets();
    const int numTriangles = mesh.GetNumberOfBoundaryTriangles();
    TriangleFace.assign(numTriangles, -1);
    for (int k = 0; k < numTriangles; ++k)
    {
      const int t = owners[k];
      const int* v = mesh.GetTet(t);
      for (int f = 0; f < 4; ++f)
      {
        const int* tri = &triangles[3 * static_cast<std::size_t>(k)];
        if (v[f] != tri[0] && v[f] != tri[1] && v[f] != tri[2])
        {
          Next[4 * static_cast<std::size_t>(t) + f] = -1 - k;
          TriangleFace[k] = 4 * t + f;
        }
      }
    }
    for (std::size_t k = 0; k < Next.size(); ++k)
    {
      if (Next[k] == unset)
      {
        throw Error("montecarlo: inconsistent mesh topology: face " + std::to_string(k % 4) +
          " of tet " + std::to_string(k / 4) + " has no neighbour and no boundary triangle");
      }
      Cells[k / 4].Next[k % 4] = Next[k];
    }
    std::vector<int>().swap(Next);
    for (int k = 0; k < numTriangles; ++k)
    {
      if (TriangleFace[k] < 0)
      {
        throw Error("montecarlo: inconsistent mesh topology: boundary triangle " +
          std::to_string(k) + " is not a face of its tet");
      }
    }
  }
};

/// One light as the photons see it: a direction rule and its own q.
struct LaunchLight
{
  LightSource::Kind Type = LightSource::Kind::Directional;
  double Direction[3] = { 0.0, 0.0, -1.0 }; ///< unit, direction of travel
  double Position[3] = { 0.0, 0.0, 0.0 };
  /// Its q at the corners of the boundary triangles, 9 per triangle
  /// (ComputeTriangleCornerIrradiance: the values whose projection is the
  /// diffusion solvers' load), W/mm^2.
  std::vector<double> Q;
};

/// A photon start inside or on the object that is not a light's triangle:
/// an isotropic point source or a pencil beam's entry point.
struct InteriorLaunch
{
  double X[3] = { 0.0, 0.0, 0.0 }; ///< mm
  double D[3] = { 0.0, 0.0, 1.0 }; ///< unit direction inside (pencil beam)
  int Tet = -1;
  int Face = -1;          ///< local face of the entry triangle (pencil beam), -1 inside
  bool Isotropic = true;  ///< point source: a uniform direction
};

/// Where the photons of one channel start: (light, triangle) pairs or
/// interior launches (Light = -1 - index into the launches) with their
/// power and its cumulative sum.
struct ChannelSource
{
  std::vector<int> Light;
  std::vector<int> Triangle;
  std::vector<double> Cumulative; ///< W, increasing, last = Power
  double Power = 0.0;             ///< W
};

void AddBalance(MonteCarloSolver::PowerBalance& to, const MonteCarloSolver::PowerBalance& from)
{
  to.Injected += from.Injected;
  to.Absorbed += from.Absorbed;
  to.Escaped += from.Escaped;
  to.RouletteGain += from.RouletteGain;
  to.Lost += from.Lost;
  to.Photons += from.Photons;
  to.LostPhotons += from.LostPhotons;
  to.Steps += from.Steps;
}

/// Tallies of one batch (one thread's scratch while it traces the batch;
/// aligned so that two threads' tallies never share a cache line).
struct alignas(128) BatchTally
{
  std::vector<double> Track; ///< per tet: sum of weight x length (W mm)
  std::vector<double> Exit;  ///< per point: escaped weight (W)
  /// Detector readings (fluence of the K detectors, then their exitance;
  /// W/mm^2) and per gate (fluence [g K + k], then exitance [G K + g K + k];
  /// J/mm^2, not yet divided by the gate width).
  std::vector<double> Detector, Gate;
  MonteCarloSolver::PowerBalance Balance;
  long long Begin = 0, End = 0;

  void Reset(int numTets, int numPoints, std::size_t detectorItems, std::size_t gateItems)
  {
    Track.assign(numTets, 0.0);
    Exit.assign(numPoints, 0.0);
    Detector.assign(detectorItems, 0.0);
    Gate.assign(gateItems, 0.0);
    Balance = MonteCarloSolver::PowerBalance();
  }
};

/// The detectors as weights on the walk's tallies (compressed rows): per tet
/// the fluence weight U_k(t) = sum over the tet's vertices i of W_k(i) / V_i
/// (the point fluence is the ring's track length / V_i), per boundary point
/// the exitance weight W_k(i) / (S_i / 3), W_k the footprint's point weights.
struct DetectorMap
{
  int Count = 0;
  std::vector<int> TetOffsets, PointOffsets;
  std::vector<std::pair<int, double>> TetWeights, PointWeights;

  void Build(const TetMesh& mesh, const std::vector<DetectorFootprint>& footprints)
  {
    Count = static_cast<int>(footprints.size());
    const int numTets = mesh.GetNumberOfTets(), numPoints = mesh.GetNumberOfPoints();
    std::vector<std::vector<std::pair<int, double>>> perPoint(numPoints);
    std::vector<std::vector<std::pair<int, double>>> tetLists(numTets);
    const std::vector<double>& vertexVolumes = mesh.GetVertexVolumes();
    const std::vector<double>& boundaryAreas = mesh.GetBoundaryAreas();
    const std::vector<int>& pointTetOffsets = mesh.GetPointTetOffsets();
    const std::vector<int>& pointTets = mesh.GetPointTets();
    for (int k = 0; k < Count; ++k)
    {
      for (const auto& [i, w] : footprints[k].GetPointWeights(mesh))
      {
        if (boundaryAreas[i] > 0.0)
        {
          perPoint[i].emplace_back(k, w / (boundaryAreas[i] / 3.0));
        }
        if (vertexVolumes[i] > 0.0)
        {
          for (int j = pointTetOffsets[i]; j < pointTetOffsets[i + 1]; ++j)
          {
            auto& list = tetLists[pointTets[j]];
            if (!list.empty() && list.back().first == k)
            {
              list.back().second += w / vertexVolumes[i];
            }
            else
            {
              list.emplace_back(k, w / vertexVolumes[i]);
            }
          }
        }
      }
    }
    auto compress = [](const std::vector<std::vector<std::pair<int, double>>>& lists,
                      std::vector<int>& offsets, std::vector<std::pair<int, double>>& flat) {
      offsets.assign(lists.size() + 1, 0);
      for (std::size_t i = 0; i < lists.size(); ++i)
      {
        offsets[i + 1] = offsets[i] + static_cast<int>(lists[i].size());
        flat.insert(flat.end(), lists[i].begin(), lists[i].end());
      }
    };
    compress(tetLists, TetOffsets, TetWeights);
    compress(perPoint, PointOffsets, PointWeights);
  }
};

/// The random walk of one channel (read-only during the tracing).
struct Tracer
{
  const TetMesh* Mesh = nullptr;
  const WalkMesh* Walk = nullptr;
  const ChannelSource* Source = nullptr;
  const std::vector<LaunchLight>* Lights = nullptr;
  const std::vector<InteriorLaunch>* Interior = nullptr;
  /// Detectors (null: none) and the time gates (GateCount 0: none).
  const DetectorMap* Detectors = nullptr;
  double GateStart = 0.0, GateEnd = 0.0, GateWidth = 1.0; ///< ns
  int GateCount = 0;
  const RayCaster* Caster = nullptr; ///< non-null: the uniform light is shadowed
  const std::vector<double>* Eta = nullptr; ///< per tet
  double Anisotropy = 0.0; ///< Henyey-Greenstein g
  double Weight = 0.0; ///< launch weight P / N (W)
  double RayOffset = 0.0, RayReach = 0.0;
  /// Bound of F_t over the outside hemisphere for every eta of the mesh
  /// (the uniform light's rejection sampling).
  double MaxUniformTransmittance = 1.0;
  std::uint64_t Seed = 1;
  int Channel = 0;

  /// Cosine-weighted unit direction about the unit vector n.
  static void CosineDirection(const double* n, PhotonRandom& rng, double* w)
  {
    double t[3], b[3];
    OrthonormalFrame(n, t, b);
    const double u = rng.Uniform(), phi = 2.0 * Pi * rng.Uniform();
    const double r = std::sqrt(u), cosTheta = std::sqrt(1.0 - u);
    const double a = r * std::cos(phi), c = r * std::sin(phi);
    for (int k = 0; k < 3; ++k)
    {
      w[k] = a * t[k] + c * b[k] + cosTheta * n[k];
    }
    Normalize(w);
  }

  /// Start a photon: position x, direction d, tet, entry face.
  void Launch(PhotonRandom& rng, double* x, double* d, int& tet, int& face) const
  {
    const ChannelSource& src = *Source;
    const double target = rng.Uniform() * src.Power;
    std::size_t e = static_cast<std::size_t>(
      std::upper_bound(src.Cumulative.begin(), src.Cumulative.end(), target) -
      src.Cumulative.begin());
    e = std::min(e, src.Cumulative.size() - 1);
    if (src.Light[e] < 0)
    {
      const InteriorLaunch& start = (*Interior)[-1 - src.Light[e]];
      std::copy(start.X, start.X + 3, x);
      tet = start.Tet;
      face = start.Face;
      if (start.Isotropic)
      {
        const double cosTheta = 2.0 * rng.Uniform() - 1.0, phi = 2.0 * Pi * rng.Uniform();
        const double sinTheta = std::sqrt(std::max(0.0, 1.0 - cosTheta * cosTheta));
        d[0] = sinTheta * std::cos(phi);
        d[1] = sinTheta * std::sin(phi);
        d[2] = cosTheta;
      }
      else
      {
        std::copy(start.D, start.D + 3, d);
      }
      return;
    }
    const LaunchLight& light = (*Lights)[src.Light[e]];
    const int tri = src.Triangle[e];
    const int* v = &Mesh->GetBoundaryTriangles()[3 * static_cast<std::size_t>(tri)];
    // A point with density proportional to the linear q: pick corner k with
    // probability q_k / sum q, then lambda_k ~ Beta(2, 2) (the median of
    // three uniforms) and the rest of the weight split uniformly.
    double q[3], qSum = 0.0;
    for (int k = 0; k < 3; ++k)
    {
      q[k] = light.Q[9 * static_cast<std::size_t>(tri) + 3 * k + Channel];
      qSum += q[k];
    }
    const double pick = rng.Uniform() * qSum;
    const int k = pick < q[0] ? 0 : (pick < q[0] + q[1] ? 1 : 2);
    double u1 = rng.Uniform(), u2 = rng.Uniform(), u3 = rng.Uniform();
    const double median = std::max(std::min(u1, u2), std::min(std::max(u1, u2), u3));
    const double split = rng.Uniform();
    double lambda[3];
    lambda[k] = median;
    lambda[(k + 1) % 3] = (1.0 - median) * split;
    lambda[(k + 2) % 3] = (1.0 - median) * (1.0 - split);
    for (int a = 0; a < 3; ++a)
    {
      x[a] = 0.0;
    }
    for (int m = 0; m < 3; ++m)
    {
      const double* p = Mesh->GetPoint(v[m]);
      for (int a = 0; a < 3; ++a)
      {
        x[a] += lambda[m] * p[a];
      }
    }
    const int code = Walk->TriangleFace[tri];
    tet = code >> 2;
    face = code & 3;
    const double* g = Walk->Cells[tet].G[face];
    double n[3] = { -g[0], -g[1], -g[2] }; // outward unit normal of the triangle
    Normalize(n);
    const double eta = (*Eta)[tet];

    // Incoming direction of travel (outside the medium).
    double in[3];
    if (light.Type == LightSource::Kind::Directional)
    {
      std::copy(light.Direction, light.Direction + 3, in);
    }
    else if (light.Type == LightSource::Kind::Point || light.Type == LightSource::Kind::Spot)
    {
      // A spot light is a point light whose cone and fall-off are in its q
      // (the launch density): the photons come from its position.
      for (int a = 0; a < 3; ++a)
      {
        in[a] = x[a] - light.Position[a];
      }
      Normalize(in);
    }
    else
    {
      // Uniform light: towards-light direction w cosine-weighted on the
      // outside hemisphere, accepted with probability F_t / max F_t (and
      // only if unoccluded when shadowed): density ~ cos F_t (V).
      double w[3] = { n[0], n[1], n[2] };
      for (int attempt = 0; attempt < 1000; ++attempt)
      {
        CosineDirection(n, rng, w);
        const double accept = Fresnel::Transmittance(std::min(1.0, Dot(w, n)), eta) /
          MaxUniformTransmittance;
        if (rng.Uniform() >= accept)
        {
          continue;
        }
        if (Caster)
        {
          const double origin[3] = { x[0] + RayOffset * (n[0] + w[0]),
            x[1] + RayOffset * (n[1] + w[1]), x[2] + RayOffset * (n[2] + w[2]) };
          if (Caster->Occluded(origin, w, RayReach))
          {
            continue;
          }
        }
        break;
      }
      for (int a = 0; a < 3; ++a)
      {
        in[a] = -w[a];
      }
    }
    // Snell refraction into the medium about the triangle's normal.
    const double cosI = -Dot(in, n);
    const double sinT2 = (1.0 - cosI * cosI) / (eta * eta);
    if (cosI <= 1e-12 || sinT2 >= 1.0)
    {
      // The light is behind this triangle (or cannot enter it): its q comes
      // from the vertex normals, which differ from the triangle's at edges
      // and silhouettes. Launch diffusely (cosine-weighted inwards).
      const double inward[3] = { -n[0], -n[1], -n[2] };
      CosineDirection(inward, rng, d);
      return;
    }
    const double cosT = std::sqrt(1.0 - sinT2);
    for (int a = 0; a < 3; ++a)
    {
      d[a] = in[a] / eta + (cosI / eta - cosT) * n[a];
    }
    Normalize(d);
  }

  /// Henyey-Greenstein scattering of the unit direction d.
  void Scatter(PhotonRandom& rng, double* d) const
  {
    double cosTheta;
    const double u = rng.Uniform();
    const double g = Anisotropy;
    if (g == 0.0)
    {
      cosTheta = 2.0 * u - 1.0;
    }
    else
    {
      const double s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
      cosTheta = std::clamp((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0);
    }
    const double sinTheta = std::sqrt(std::max(0.0, 1.0 - cosTheta * cosTheta));
    const double phi = 2.0 * Pi * rng.Uniform();
    const double cosPhi = std::cos(phi), sinPhi = std::sin(phi);
    double out[3];
    if (std::abs(d[2]) > 0.99999)
    {
      out[0] = sinTheta * cosPhi;
      out[1] = sinTheta * sinPhi;
      out[2] = (d[2] > 0.0 ? 1.0 : -1.0) * cosTheta;
    }
    else
    {
      const double r = std::sqrt(1.0 - d[2] * d[2]);
      out[0] = sinTheta * (d[0] * d[2] * cosPhi - d[1] * sinPhi) / r + d[0] * cosTheta;
      out[1] = sinTheta * (d[1] * d[2] * cosPhi + d[0] * sinPhi) / r + d[1] * cosTheta;
      out[2] = -sinTheta * cosPhi * r + d[2] * cosTheta;
    }
    std::copy(out, out + 3, d);
    Normalize(d);
  }

  /// Russian roulette on a low weight; false if the photon died.
  static bool Roulette(PhotonRandom& rng, double threshold, double& w,
    MonteCarloSolver::PowerBalance& balance)
  {
    if (w >= threshold)
    {
      return true;
    }
    if (rng.Uniform() < RouletteSurvival)
    {
      const double survivor = w / RouletteSurvival;
      balance.RouletteGain += survivor - w;
      w = survivor;
      return true;
    }
    balance.RouletteGain -= w;
    w = 0.0;
    return false;
  }

  /// The detectors' fluence over a segment of length `length` (mm) in tet
  /// t, started at `time` (ns) with weight w0: `track` is its track-length
  /// integral (W mm); per gate, the part of it inside the gate.
  void TallyDetectorFluence(int t, double w0, double length, double muA, double track,
    double time, BatchTally& tally) const
  {
    const DetectorMap& map = *Detectors;
    const int first = map.TetOffsets[t], last = map.TetOffsets[t + 1];
    if (first == last)
    {
      return; // no detector reads this tet: nothing to split into gates either
    }
    for (int j = first; j < last; ++j)
    {
      tally.Detector[map.TetWeights[j].first] += track * map.TetWeights[j].second;
    }
    if (GateCount == 0)
    {
      return;
    }
    const double speed = SpeedOfLightMillimetresPerNanosecond / (*Eta)[t]; // mm/ns
    const double end = time + length / speed;
    if (end <= GateStart || time >= GateEnd)
    {
      return;
    }
    const int k0 = std::max(0, static_cast<int>(std::floor((time - GateStart) / GateWidth)) - 1);
    for (int g = k0; g < GateCount; ++g)
    {
      const double g0 = GateStart + g * GateWidth, g1 = GateStart + (g + 1) * GateWidth;
      if (g0 >= end)
      {
        break;
      }
      const double a = std::max(time, g0), b = std::min(end, g1);
      if (!(b > a))
      {
        continue;
      }
      const double s1 = (a - time) * speed, s2 = (b - time) * speed;
      const double part = muA > 0.0
        ? w0 * (std::exp(-muA * s1) - std::exp(-muA * s2)) / muA
        : w0 * (s2 - s1);
      double* gate = &tally.Gate[static_cast<std::size_t>(g) * map.Count];
      for (int j = first; j < last; ++j)
      {
        gate[map.TetWeights[j].first] += part * map.TetWeights[j].second;
      }
    }
  }

  /// The detectors' exitance of weight `w` escaping at point i at `time` (ns).
  void TallyDetectorExit(int i, double w, double time, BatchTally& tally) const
  {
    const DetectorMap& map = *Detectors;
    const int first = map.PointOffsets[i], last = map.PointOffsets[i + 1];
    if (first == last)
    {
      return;
    }
    for (int j = first; j < last; ++j)
    {
      tally.Detector[map.Count + map.PointWeights[j].first] += w * map.PointWeights[j].second;
    }
    if (GateCount == 0 || time < GateStart || time >= GateEnd)
    {
      return;
    }
    const int g = std::clamp(
      static_cast<int>(std::floor((time - GateStart) / GateWidth)), 0, GateCount - 1);
    double* gate = &tally.Gate[(static_cast<std::size_t>(GateCount) + g) * map.Count];
    for (int j = first; j < last; ++j)
    {
      gate[map.PointWeights[j].first] += w * map.PointWeights[j].second;
    }
  }

  /// Trace: the exit face of the ray (x, d) in cell pl, the nearest face
  /// it moves towards (not `entry`, the one it just came in through, unless
  /// nothing else is left by rounding), or -1; and its distance (infinite
  /// for -1). Distances lambda_f / (-G_f . d) compared without dividing:
  /// a/b < c/e  <=>  a e < c b for positive b, e.
  int ExitFace(const TetCell& pl, const double x[3], const double d[3], int entry,
    double& exitDistance) const
  {
    double gd[4];
    gd[1] = Dot(pl.G[1], d);
    gd[2] = Dot(pl.G[2], d);
    gd[3] = Dot(pl.G[3], d);
    gd[0] = -(gd[1] + gd[2] + gd[3]); // the gradients sum to 0
    double bestLambda = 1.0, bestRate = 0.0; // distance bestLambda / bestRate
    int exitFace = -1;
    for (int pass = 0; pass < 2 && exitFace < 0; ++pass)
    {
      for (int f = 0; f < 4; ++f)
      {
        if ((f == entry) != (pass == 1) || !(gd[f] < 0.0))
        {
          continue;
        }
        const double lambda = std::max(0.0, Dot(pl.G[f], x) + pl.E[f]);
        if (exitFace < 0 || lambda * bestRate < bestLambda * -gd[f])
        {
          bestLambda = lambda;
          bestRate = -gd[f];
          exitFace = f;
        }
      }
    }
    exitDistance = exitFace < 0 ? std::numeric_limits<double>::infinity() : bestLambda / bestRate;
    return exitFace;
  }

  /// Trace, escape through `exitFace` of tet t at x: the weight w shared
  /// among the triangle's corners by their barycentric coordinates there
  /// (exitance tally and detectors).
  void Escape(const TetCell& pl, int t, int exitFace, const double x[3], double w, double time,
    bool detectors, BatchTally& tally) const
  {
    const int* tets = Mesh->GetTets().data();
    double lambda[4], sum = 0.0;
    for (int a = 0; a < 4; ++a)
    {
      lambda[a] = a == exitFace ? 0.0 : std::max(0.0, Dot(pl.G[a], x) + pl.E[a]);
      sum += lambda[a];
    }
    for (int a = 0; a < 4; ++a)
    {
      if (a != exitFace)
      {
        const double share = sum > 0.0 ? lambda[a] / sum : 1.0 / 3.0;
        const int point = tets[4 * static_cast<std::size_t>(t) + a];
        tally.Exit[point] += w * share;
        if (detectors)
        {
          TallyDetectorExit(point, w * share, time, tally);
        }
      }
    }
  }

  /// Trace photon number `index` of this channel into the batch tally.
  void Trace(long long index, BatchTally& tally) const
  {
    PhotonRandom rng(Seed, Channel, index);
    double x[3], d[3];
    int t, entry;
    Launch(rng, x, d, t, entry);
    double w = Weight;
    // Local copy: updated every step, added to the batch at the end.
    MonteCarloSolver::PowerBalance balance;
    balance.Injected += w;
    ++balance.Photons;
    const double threshold = RouletteThreshold * Weight;
    double tau = -std::log(rng.OpenUniform()); // optical depth to the next scattering
    double time = 0.0; // ns since the emission (time of flight)
    const bool detectors = Detectors && Detectors->Count > 0;
    int zeroSteps = 0;
    for (long long step = 0;; ++step)
    {
      if (step >= MaxSteps)
      {
        balance.Lost += w;
        ++balance.LostPhotons;
        break;
      }
      const TetCell& pl = Walk->Cells[t];
      // Exit face: the nearest face the ray moves towards (not the one it
      // just came in through, unless nothing else is left by rounding).
      double exitDistance;
      const int exitFace = ExitFace(pl, x, d, entry, exitDistance);
      const double muS = pl.MuS, muA = pl.MuA;
      const double scatterDistance =
        muS > 0.0 ? tau / muS : std::numeric_limits<double>::infinity();
      const bool scatters = scatterDistance < exitDistance;
      if (!scatters && exitFace < 0)
      {
        balance.Lost += w; // no way out of the tet (rounding): give up
        ++balance.LostPhotons;
        break;
      }
      const double length = scatters ? scatterDistance : exitDistance;
      // Continuous absorption: the weight lost on the segment is absorbed
      // there; its track-length fluence integral is that / mu_a.
      const double w0 = w;
      double track;
      if (muA > 0.0)
      {
        const double absorbed = -w * std::expm1(-muA * length);
        track = absorbed / muA;
        balance.Absorbed += absorbed;
        w -= absorbed;
      }
      else
      {
        track = w * length;
      }
      tally.Track[t] += track;
      if (detectors)
      {
        TallyDetectorFluence(t, w0, length, muA, track, time, tally);
        time += length * (*Eta)[t] / SpeedOfLightMillimetresPerNanosecond;
      }
      for (int a = 0; a < 3; ++a)
      {
        x[a] += length * d[a];
      }
      ++balance.Steps;
      if (scatters)
      {
        Scatter(rng, d);
        tau = -std::log(rng.OpenUniform());
        entry = -1;
        zeroSteps = 0;
        if (!Roulette(rng, threshold, w, balance))
        {
          break;
        }
        continue;
      }
      tau = std::max(0.0, tau - muS * length);
      if (length > 0.0)
      {
        zeroSteps = 0;
      }
      else if (++zeroSteps > MaxZeroSteps)
      {
        balance.Lost += w;
        ++balance.LostPhotons;
        break;
      }
      const int code = pl.Next[exitFace];
      if (code >= 0)
      {
        t = code >> 2; // index-matched interior face: walk on
        entry = code & 3;
        continue;
      }
      // Boundary face: Fresnel reflection or escape.
      double n[3] = { -pl.G[exitFace][0], -pl.G[exitFace][1], -pl.G[exitFace][2] };
      Normalize(n);
      const double cosI = std::min(1.0, Dot(d, n));
      const double eta = (*Eta)[t];
      const double sinT2 = eta * eta * std::max(0.0, 1.0 - cosI * cosI);
      // Reflectance(cos outside, eta) equals the reflectance seen from inside
      // at the matching angle (reciprocity); sin_t >= 1 is total reflection.
      const double reflectance =
        sinT2 >= 1.0 ? 1.0 : Fresnel::Reflectance(std::sqrt(1.0 - sinT2), eta);
      if (reflectance >= 1.0 || rng.Uniform() < reflectance)
      {
        const double dn = Dot(d, n);
        for (int a = 0; a < 3; ++a)
        {
          d[a] -= 2.0 * dn * n[a];
        }
        entry = exitFace;
        if (!Roulette(rng, threshold, w, balance))
        {
          break;
        }
        continue;
      }
      // Escape: share the weight among the triangle's corners by their
      // barycentric coordinates at the exit point.
      Escape(pl, t, exitFace, x, w, time, detectors, tally);
      balance.Escaped += w;
      break;
    }
    AddBalance(tally.Balance, balance);
  }
};

using Progress = std::function<bool(double)>;

/// What the photons start from: the lights with their own q, the interior
/// launches (point sources, pencil beams) and, per channel, the table of
/// (light, triangle) pairs with the cumulative power to draw from.
struct LaunchTables
{
  std::vector<LaunchLight> Lights;
  std::vector<InteriorLaunch> Interior;
  std::vector<std::array<double, NumberOfChannels>> InteriorPower;
  std::vector<std::pair<std::size_t, int>> PencilTriangles; // (launch, boundary triangle)
  std::array<ChannelSource, NumberOfChannels> Sources;
};

/// Set-up: each light of the problem (checked, with its q alone) and the
/// uniform light. False if the progress callback asked to abort.
bool PrepareLights(const DiffusionProblem& problem, int uniformSamples, const Progress& progress,
  std::vector<LaunchLight>& lights)
{
  const TetMesh& mesh = *problem.Mesh;
  const OpticalProperties& material = *problem.Material;
  bool aborted = false;
  auto abortCheck = [&progress, &aborted]() {
    aborted = aborted || !progress(0.0);
    return aborted;
  };
  for (std::size_t l = 0; l < problem.Lights.size(); ++l)
  {
    const LightSource& source = problem.Lights[l];
    LaunchLight light;
    light.Type = source.Type;
    for (int a = 0; a < 3; ++a)
    {
      light.Direction[a] = source.Direction[a];
      light.Position[a] = source.Position[a];
    }
    // Checks the light and computes its q alone.
    try
    {
      if (!ComputeTriangleCornerIrradiance(mesh, material.RefractiveIndex, { source }, 0.0, 0,
            problem.Shadows, light.Q, abortCheck))
      {
        return false;
      }
    }
    catch (const Error& e)
    {
      throw Error("montecarlo: light " + std::to_string(l) + " of the problem: " + e.what());
    }
    if (light.Type == LightSource::Kind::Directional)
    {
      Normalize(light.Direction);
    }
    lights.push_back(std::move(light));
  }
  if (problem.UniformIrradiance > 0.0)
  {
    LaunchLight light;
    light.Type = LightSource::Kind::Uniform;
    if (!ComputeTriangleCornerIrradiance(mesh, material.RefractiveIndex, {}, problem.UniformIrradiance,
          uniformSamples, problem.Shadows, light.Q, abortCheck))
    {
      return false;
    }
    lights.push_back(std::move(light));
  }
  return true;
}

/// Set-up: point sources placed in their tets, pencil beams at their entry
/// points (the errors name the source).
void PlaceInteriorSources(const DiffusionProblem& problem, LaunchTables& tables)
{
  if (!problem.HasInteriorSources())
  {
    return;
  }
  const TetMesh& mesh = *problem.Mesh;
  const OpticalProperties& material = *problem.Material;
  const Sources& all = *problem.InteriorSources;
  Sources points;
  for (const PointSource& point : all.GetPointSources())
  {
    points.AddPointSource(point);
  }
  try
  {
    all.Validate();
    for (const PlacedSource& placed : points.Place(mesh, material))
    {
      InteriorLaunch start;
      std::copy(placed.Source.Position.begin(), placed.Source.Position.end(), start.X);
      start.Tet = placed.Tet;
      tables.Interior.push_back(start);
      tables.InteriorPower.push_back(placed.Source.Power);
    }
    const std::vector<PencilBeam>& pencils = all.GetPencilBeams();
    const double tolerance = pencils.empty() ? 0.0 : SurfaceTolerance(mesh);
    for (std::size_t k = 0; k < pencils.size(); ++k)
    {
      const PencilBeam& beam = pencils[k];
      const std::string name =
        beam.Label.empty() ? "pencil beam " + std::to_string(k + 1) : beam.Label;
      const PencilEntry entry = LocatePencilEntry(mesh, material, beam, name, tolerance);
      InteriorLaunch start;
      std::copy(entry.Surface.Position.begin(), entry.Surface.Position.end(), start.X);
      std::copy(entry.Refracted.begin(), entry.Refracted.end(), start.D);
      start.Isotropic = false;
      tables.Interior.push_back(start);
      std::array<double, NumberOfChannels> power{};
      for (int c = 0; c < NumberOfChannels; ++c)
      {
        power[c] = entry.Transmitted * beam.Power[c];
      }
      tables.InteriorPower.push_back(power);
      tables.PencilTriangles.push_back({ tables.Interior.size() - 1, entry.Surface.Triangle });
    }
  }
  catch (const Error& e)
  {
    throw Error(std::string("montecarlo: ") + e.what());
  }
}

/// Set-up: the detectors' footprints (the errors of ReadDetectors).
std::vector<DetectorFootprint> LocateFootprints(
  const TetMesh& mesh, const std::vector<Detector>& detectors)
{
  try
  {
    return LocateDetectors(mesh, detectors);
  }
  catch (const Error& e)
  {
    throw Error(std::string("montecarlo: ") + e.what());
  }
}

/// Set-up: per channel, the power through each boundary triangle: S_f x
/// mean of its corner values (the vertex rule for the integral of q over f;
/// the diffusion solvers' loads S_i q_i / 3 of the projected q sum to the
/// same total), then the interior launches.
void BuildChannelSources(const TetMesh& mesh, LaunchTables& tables)
{
  const std::vector<double>& areas = mesh.GetBoundaryTriangleAreas();
  const int numTriangles = mesh.GetNumberOfBoundaryTriangles();
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    ChannelSource& src = tables.Sources[c];
    double total = 0.0;
    for (std::size_t l = 0; l < tables.Lights.size(); ++l)
    {
      const std::vector<double>& q = tables.Lights[l].Q;
      for (int f = 0; f < numTriangles; ++f)
      {
        const double* qf = &q[9 * static_cast<std::size_t>(f) + c];
        const double power = areas[f] * (qf[0] + qf[3] + qf[6]) / 3.0;
        if (power > 0.0)
        {
          total += power;
          src.Light.push_back(static_cast<int>(l));
          src.Triangle.push_back(f);
          src.Cumulative.push_back(total);
        }
      }
    }
    for (std::size_t s = 0; s < tables.Interior.size(); ++s)
    {
      const double power = tables.InteriorPower[s][c];
      if (power > 0.0)
      {
        total += power;
        src.Light.push_back(-1 - static_cast<int>(s));
        src.Triangle.push_back(-1);
        src.Cumulative.push_back(total);
      }
    }
    src.Power = total;
  }
}

/// Max over the outside hemisphere of F_t (the uniform light's rejection
/// bound), per distinct eta would be exact; F_t is largest at normal
/// incidence for an unpolarised smooth interface, checked on a grid.
double MaxUniformTransmittance(const std::vector<double>& refractiveIndex)
{
  auto maxTransmittance = [](double eta) {
    double best = Fresnel::Transmittance(1.0, eta);
    for (int k = 0; k <= 1024; ++k)
    {
      best = std::max(best, Fresnel::Transmittance(k / 1024.0, eta));
    }
    return best;
  };
  std::vector<double> etas(refractiveIndex);
  std::sort(etas.begin(), etas.end());
  etas.erase(std::unique(etas.begin(), etas.end()), etas.end());
  if (etas.size() > 64)
  {
    return 1.0; // correct for any eta, only slower to accept
  }
  double maxFt = 0.0;
  for (double eta : etas)
  {
    maxFt = std::max(maxFt, maxTransmittance(eta));
  }
  return maxFt;
}

/// The sizes of the tracing: photons per channel split into batches, run
/// `Slots` batches at a time (one per thread).
struct BatchPlan
{
  long long Photons = 0;
  int Batches = 0;
  /// The batches this process traces (all of them in one process; every
  /// size-th from its rank when the run is shared).
  std::vector<int> Mine;
  int Threads = 0;
  int Slots = 0;
  double TotalPhotons = 0.0; ///< over the lit channels (progress)
  /// The first photon of batch b (b = Batches: the end).
  long long Begin(long long b) const { return b * Photons / Batches; }
  int NumTets = 0, NumPoints = 0;
  std::size_t DetectorItems = 0, GateItems = 0;
};

/// Tracing: the sizes of the run of `solver` (its photons, threads,
/// batches and time gates) on `mesh` with the sources of `tables` and
/// `detectors` detectors.
BatchPlan MakeBatchPlan(const MonteCarloSolver& solver, const TetMesh& mesh,
  const LaunchTables& tables, int detectors, int shareRank, int shareSize)
{
  const TimeGates& gates = solver.GetTimeGates();
  BatchPlan plan;
  plan.Photons = solver.GetNumberOfPhotons();
  plan.Threads =
    solver.GetNumberOfThreads() > 0 ? solver.GetNumberOfThreads() : omp_get_max_threads();
  int litChannels = 0;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    litChannels += tables.Sources[c].Power > 0.0 ? 1 : 0;
  }
  plan.NumTets = mesh.GetNumberOfTets();
  plan.NumPoints = mesh.GetNumberOfPoints();
  plan.DetectorItems = 2 * static_cast<std::size_t>(detectors);
  plan.GateItems = gates.Count != 0 ? plan.DetectorItems * gates.Count : 0;
  plan.Batches =
    static_cast<int>(std::min<long long>(solver.GetNumberOfBatches(), plan.Photons));
  long long mine = 0; // this process's photons per channel (progress)
  for (int b = shareRank; b < plan.Batches; b += shareSize)
  {
    plan.Mine.push_back(b);
    mine += plan.Begin(b + 1) - plan.Begin(b);
  }
  plan.TotalPhotons = static_cast<double>(mine) * std::max(1, litChannels);
  plan.Slots = std::min(plan.Threads, static_cast<int>(plan.Mine.size()));
  return plan;
}

/// Sums over the batches b (photons n_b, tallies T_b): A1 = sum T_b and
/// A2 = sum T_b^2 / n_b, per tet (A1 only), per point and per detector item.
struct BatchSums
{
  std::vector<double> TetSum, FluenceA1, FluenceA2, ExitA1, ExitA2;
  std::vector<double> DetectorA1, DetectorA2, GateA1, GateA2;

  explicit BatchSums(const BatchPlan& plan)
    : TetSum(plan.NumTets)
    , FluenceA1(plan.NumPoints)
    , FluenceA2(plan.NumPoints)
    , ExitA1(plan.NumPoints)
    , ExitA2(plan.NumPoints)
    , DetectorA1(plan.DetectorItems)
    , DetectorA2(plan.DetectorItems)
    , GateA1(plan.GateItems)
    , GateA2(plan.GateItems)
  {
  }
  void Clear()
  {
    for (std::vector<double>* v : { &TetSum, &FluenceA1, &FluenceA2, &ExitA1, &ExitA2,
           &DetectorA1, &DetectorA2, &GateA1, &GateA2 })
    {
      std::fill(v->begin(), v->end(), 0.0);
    }
  }
};

/// Tracing: the batches of one channel, `Slots` at a time, each added to
/// the sums in batch order (deterministic for any thread count). Sets
/// `stop` when the progress callback asks to abort.
void TraceBatches(const Tracer& tracer, const BatchPlan& plan, const TetMesh& mesh,
  const Progress& progress, std::vector<BatchTally>& tallies, BatchSums& sums,
  MonteCarloSolver::PowerBalance& balance, std::atomic<long long>& done, std::atomic<bool>& stop)
{
  const std::vector<int>& pointTetOffsets = mesh.GetPointTetOffsets();
  const std::vector<int>& pointTets = mesh.GetPointTets();
  const int numTets = plan.NumTets, numPoints = plan.NumPoints;
  const int slots = plan.Slots, threads = plan.Threads;
  const int mine = static_cast<int>(plan.Mine.size());
  for (int first = 0; first < mine && !stop; first += slots)
  {
    const int count = std::min(slots, mine - first);
    // One batch per thread; only thread 0 (the calling thread) reports.
#pragma omp parallel for num_threads(count) schedule(static, 1)
    for (int k = 0; k < count; ++k)
    {
      BatchTally& tally = tallies[k];
      tally.Reset(numTets, numPoints, plan.DetectorItems, plan.GateItems);
      const long long b = plan.Mine[first + k];
      tally.Begin = plan.Begin(b);
      tally.End = plan.Begin(b + 1);
      for (long long p = tally.Begin; p < tally.End && !stop.load(std::memory_order_relaxed);
           p += Chunk)
      {
        const long long end = std::min(tally.End, p + Chunk);
        for (long long i = p; i < end; ++i)
        {
          tracer.Trace(i, tally);
        }
        const long long total = done.fetch_add(end - p) + (end - p);
        if (omp_get_thread_num() == 0 && !progress(total / plan.TotalPhotons))
        {
          stop = true;
        }
      }
    }
    if (stop)
    {
      break;
    }
    // Add the batches in batch order (deterministic for any thread count);
    // in parallel only when it pays for a thread team.
    const bool parallelSum = static_cast<long long>(count) * (numTets + numPoints) > 1000000;
#pragma omp parallel for num_threads(threads) schedule(static) if (parallelSum)
    for (int t = 0; t < numTets; ++t)
    {
      for (int k = 0; k < count; ++k)
      {
        sums.TetSum[t] += tallies[k].Track[t];
      }
    }
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1024) if (parallelSum)
    for (int i = 0; i < numPoints; ++i)
    {
      for (int k = 0; k < count; ++k)
      {
        const BatchTally& tally = tallies[k];
        const double n = static_cast<double>(tally.End - tally.Begin);
        double track = 0.0;
        for (int j = pointTetOffsets[i]; j < pointTetOffsets[i + 1]; ++j)
        {
          track += tally.Track[pointTets[j]];
        }
        sums.FluenceA1[i] += track;
        sums.FluenceA2[i] += track * track / n;
        const double out = tally.Exit[i];
        sums.ExitA1[i] += out;
        sums.ExitA2[i] += out * out / n;
      }
    }
    for (int k = 0; k < count; ++k)
    {
      const BatchTally& tally = tallies[k];
      const double n = static_cast<double>(tally.End - tally.Begin);
      for (std::size_t m = 0; m < plan.DetectorItems; ++m)
      {
        sums.DetectorA1[m] += tally.Detector[m];
        sums.DetectorA2[m] += tally.Detector[m] * tally.Detector[m] / n;
      }
      for (std::size_t m = 0; m < plan.GateItems; ++m)
      {
        sums.GateA1[m] += tally.Gate[m];
        sums.GateA2[m] += tally.Gate[m] * tally.Gate[m] / n;
      }
      AddBalance(balance, tally.Balance);
    }
  }
}

/// A run shared by several processes (MonteCarloSolver::SetShare): one
/// channel's batch sums and power balance become their sums over the
/// processes (`sum`: collective), and `stop` true on every process if one
/// stopped (that is agreed first, so every process makes the same calls).
void AddOverShare(const std::function<void(double*, std::size_t)>& sum, BatchSums& sums,
  MonteCarloSolver::PowerBalance& balance, std::atomic<bool>& stop)
{
  MonteCarloSolver::PowerBalance& b = balance;
  // The counts are below 2^53 (4.3e9 photons at most, MaxPhotons): exact as doubles.
  double small[] = { stop ? 1.0 : 0.0, b.Injected, b.Absorbed, b.Escaped, b.RouletteGain, b.Lost,
    static_cast<double>(b.Photons), static_cast<double>(b.LostPhotons),
    static_cast<double>(b.Steps) };
  sum(small, sizeof(small) / sizeof(small[0]));
  stop = small[0] > 0.0;
  b.Injected = small[1];
  b.Absorbed = small[2];
  b.Escaped = small[3];
  b.RouletteGain = small[4];
  b.Lost = small[5];
  b.Photons = std::llround(small[6]);
  b.LostPhotons = std::llround(small[7]);
  b.Steps = std::llround(small[8]);
  if (stop)
  {
    return;
  }
  for (std::vector<double>* v : { &sums.TetSum, &sums.FluenceA1, &sums.FluenceA2, &sums.ExitA1,
         &sums.ExitA2, &sums.DetectorA1, &sums.DetectorA2, &sums.GateA1, &sums.GateA2 })
  {
    sum(v->data(), v->size());
  }
}

/// The results of the tracing, channel by channel.
struct Estimates
{
  std::vector<double> TetFluence, PointFluence, PointFluenceError, Exitance, ExitanceError;
  std::array<MonteCarloSolver::PowerBalance, NumberOfChannels> Balances{};
  std::vector<DetectorReading> Readings, ReadingErrors;
  std::vector<std::vector<DetectorReading>> GateReadings, GateErrors;

  Estimates(const BatchPlan& plan, const std::vector<DetectorFootprint>& footprints,
    int gateCount)
    : TetFluence(3 * static_cast<std::size_t>(plan.NumTets), 0.0)
    , PointFluence(3 * static_cast<std::size_t>(plan.NumPoints), 0.0)
    , PointFluenceError(3 * static_cast<std::size_t>(plan.NumPoints), 0.0)
    , Exitance(3 * static_cast<std::size_t>(plan.NumPoints), 0.0)
    , ExitanceError(3 * static_cast<std::size_t>(plan.NumPoints), 0.0)
    , Readings(footprints.size())
    , ReadingErrors(footprints.size())
    , GateReadings(gateCount, std::vector<DetectorReading>(footprints.size()))
  {
    GateErrors = GateReadings;
    for (std::size_t k = 0; k < footprints.size(); ++k)
    {
      Readings[k].SurfacePosition = footprints[k].SurfacePosition;
      Readings[k].Area = footprints[k].Area;
      ReadingErrors[k] = Readings[k];
      for (std::size_t g = 0; g < GateReadings.size(); ++g)
      {
        GateReadings[g][k] = Readings[k];
        GateErrors[g][k] = Readings[k];
      }
    }
  }
};

/// Read-out of channel c from the batch sums. Batch estimates
/// X_b = T_b N / (n_b D) (D = V_i or S_i / 3): the mean is A1 / D and the
/// variance of the mean (sum n_b X_b^2 - N X^2) / ((B - 1) N) =
/// (N A2 - A1^2) / ((B - 1) D^2).
void StoreChannelEstimates(int c, const BatchSums& sums, const BatchPlan& plan,
  const TetMesh& mesh, const TimeGates& gates, Estimates& out)
{
  const std::vector<double>& tetVolumes = mesh.GetTetVolumes();
  const std::vector<double>& vertexVolumes = mesh.GetVertexVolumes();
  const std::vector<double>& boundaryAreas = mesh.GetBoundaryAreas();
  const int numBatches = plan.Batches;
  const bool timed = gates.Count != 0;
  const double n = static_cast<double>(plan.Photons);
  const double dof = numBatches - 1;
  for (int t = 0; t < plan.NumTets; ++t)
  {
    out.TetFluence[3 * static_cast<std::size_t>(t) + c] = sums.TetSum[t] / tetVolumes[t];
  }
  auto standardError = [&](double a1, double a2, double measure) {
    if (numBatches < 2)
    {
      return std::numeric_limits<double>::quiet_NaN(); // one photon: undefined
    }
    return std::sqrt(std::max(0.0, n * a2 - a1 * a1) / dof) / measure;
  };
  for (int i = 0; i < plan.NumPoints; ++i)
  {
    const std::size_t ic = 3 * static_cast<std::size_t>(i) + c;
    if (vertexVolumes[i] > 0.0)
    {
      out.PointFluence[ic] = sums.FluenceA1[i] / vertexVolumes[i];
      out.PointFluenceError[ic] =
        standardError(sums.FluenceA1[i], sums.FluenceA2[i], vertexVolumes[i]);
    }
    if (boundaryAreas[i] > 0.0)
    {
      const double s = boundaryAreas[i] / 3.0;
      out.Exitance[ic] = sums.ExitA1[i] / s;
      out.ExitanceError[ic] = standardError(sums.ExitA1[i], sums.ExitA2[i], s);
    }
  }
  // Detectors: the tallies are the readings (the weights hold the
  // measures); the gate sums become gate averages (/ width).
  const int numDetectors = static_cast<int>(out.Readings.size());
  for (int k = 0; k < numDetectors; ++k)
  {
    const std::size_t f = k, e = numDetectors + static_cast<std::size_t>(k);
    out.Readings[k].Fluence[c] = sums.DetectorA1[f];
    out.Readings[k].Exitance[c] = sums.DetectorA1[e];
    out.ReadingErrors[k].Fluence[c] = standardError(sums.DetectorA1[f], sums.DetectorA2[f], 1.0);
    out.ReadingErrors[k].Exitance[c] = standardError(sums.DetectorA1[e], sums.DetectorA2[e], 1.0);
    for (int g = 0; timed && g < gates.Count; ++g)
    {
      const double width = gates.GetWidth();
      const std::size_t gf = static_cast<std::size_t>(g) * numDetectors + k;
      const std::size_t ge = (static_cast<std::size_t>(gates.Count) + g) * numDetectors + k;
      out.GateReadings[g][k].Fluence[c] = sums.GateA1[gf] / width;
      out.GateReadings[g][k].Exitance[c] = sums.GateA1[ge] / width;
      out.GateErrors[g][k].Fluence[c] = standardError(sums.GateA1[gf], sums.GateA2[gf], width);
      out.GateErrors[g][k].Exitance[c] = standardError(sums.GateA1[ge], sums.GateA2[ge], width);
    }
  }
}

/// Outputs: radiance along the normal implied by eq. 3's angular form:
/// L_o(w) = C F_t(w) (TransCut eq. 3), so M = int L_o cos dw = C pi
/// UniformTransmittance(eta) and L_n = M F_t(1) / (pi UniformTransmittance).
void ExitanceToRadiance(const TetMesh& mesh, const std::vector<double>& pointEta,
  const Estimates& estimates, std::vector<double>& radiance, std::vector<double>& radianceError)
{
  radiance.assign(estimates.Exitance.size(), 0.0);
  radianceError.assign(estimates.Exitance.size(), 0.0);
  for (int i : mesh.GetBoundaryPoints())
  {
    const double eta = pointEta[i];
    const double toRadiance =
      Fresnel::Transmittance(1.0, eta) / (Pi * Fresnel::UniformTransmittance(eta));
    for (int c = 0; c < NumberOfChannels; ++c)
    {
      const std::size_t ic = 3 * static_cast<std::size_t>(i) + c;
      radiance[ic] = estimates.Exitance[ic] * toRadiance;
      radianceError[ic] = estimates.ExitanceError[ic] * toRadiance;
    }
  }
}

/// Set-up: the pencil beams' entry tets and faces from their triangles.
void AttachPencilEntries(const WalkMesh& walk, LaunchTables& tables)
{
  for (const auto& [launch, triangle] : tables.PencilTriangles)
  {
    const int code = walk.TriangleFace[triangle];
    tables.Interior[launch].Tet = code >> 2;
    tables.Interior[launch].Face = code & 3;
  }
}

/// Tracing: the walk's coefficients of channel c (scattering sigma_s' /
/// (1 - g), absorption mu_a).
void SetChannelCoefficients(
  const OpticalProperties& material, int c, double anisotropy, WalkMesh& walk)
{
  const int numTets = static_cast<int>(walk.Cells.size());
  for (int t = 0; t < numTets; ++t)
  {
    TetCell& cell = walk.Cells[t];
    cell.MuS = material.ReducedScatteringCoefficient[3 * static_cast<std::size_t>(t) + c] /
      (1.0 - anisotropy);
    cell.MuA = material.AbsorptionCoefficient[3 * static_cast<std::size_t>(t) + c];
  }
}

/// Outputs: the report of a Monte Carlo solve (no linear solve: 0
/// iterations, converged), memory of the tallies, the walk and the tables.
SolverReport MakeReport(const std::string& name, int numTets, std::size_t bytes,
  const LaunchTables& tables, double setupMs, double solveMs)
{
  SolverReport report;
  report.Solver = name;
  report.LinearSolver = "photons";
  report.NumberOfUnknowns = numTets; // tally cells per channel
  report.NumberOfNonZeros = 0;
  report.MemoryBytes = bytes;
  for (const LaunchLight& light : tables.Lights)
  {
    report.MemoryBytes += light.Q.size() * sizeof(double);
  }
  for (const ChannelSource& src : tables.Sources)
  {
    report.MemoryBytes += src.Cumulative.size() * (sizeof(double) + 2 * sizeof(int));
  }
  report.SetupMilliseconds = setupMs;
  report.SolveMilliseconds = solveMs;
  for (int c = 0; c < NumberOfChannels; ++c)
  {
    report.Iterations[c] = 0;
    report.Residual[c] = 0.0;
    report.Converged[c] = true;
  }
  return report;
}

/// Solve's input checks (before any work): the errors listed at Solve.
void CheckInputs(const MonteCarloSolver& solver, const DiffusionProblem& problem)
{
  const long long numberOfPhotons = solver.GetNumberOfPhotons();
  const long long maxPhotons = solver.GetMaxPhotons();
  const int numberOfBatches = solver.GetNumberOfBatches();
  const double anisotropy = solver.GetAnisotropy();
  const int numberOfThreads = solver.GetNumberOfThreads();
  const int uniformLightSamples = solver.GetUniformLightSamples();
  const TimeGates& gates = solver.GetTimeGates();
  if (!problem.Mesh || !problem.Material)
  {
    throw Error("montecarlo: the problem needs a mesh and a material");
  }
  const TetMesh& mesh = *problem.Mesh;
  const int numTets = mesh.GetNumberOfTets();
  if (numTets == 0)
  {
    throw Error("montecarlo: the mesh has no tets");
  }
  const OpticalProperties& material = *problem.Material;
  material.Validate(numTets);
  if (numberOfPhotons <= 0)
  {
    throw Error("montecarlo: number of photons " + std::to_string(numberOfPhotons) +
      ": must be > 0");
  }
  if (numberOfPhotons > maxPhotons && !GetLongRunsAllowed())
  {
    throw Error("montecarlo: " + std::to_string(numberOfPhotons) +
      " photons per channel (--photons) are above the budget of " + std::to_string(maxPhotons) +
      " (hours of tracing): use fewer photons (or " + LongRunOverride() +
      ", or MonteCarlo::SetMaxPhotons)");
  }
  if (numberOfBatches < 2)
  {
    throw Error("montecarlo: number of batches " + std::to_string(numberOfBatches) +
      ": must be >= 2 (the standard errors come from the batches)");
  }
  if (!(anisotropy > -1.0 && anisotropy < 1.0))
  {
    std::ostringstream msg;
    msg << "montecarlo: anisotropy g = " << anisotropy << ": must be in (-1, 1)";
    throw Error(msg.str());
  }
  if (numberOfThreads < 0)
  {
    throw Error("montecarlo: number of threads " + std::to_string(numberOfThreads) +
      ": must be >= 0 (0: OpenMP default)");
  }
  if (uniformLightSamples < 0)
  {
    throw Error("montecarlo: uniform light samples " + std::to_string(uniformLightSamples) +
      ": must be >= 0");
  }
  if (!(problem.UniformIrradiance >= 0.0) || !std::isfinite(problem.UniformIrradiance))
  {
    std::ostringstream msg;
    msg << "montecarlo: uniform irradiance " << problem.UniformIrradiance
        << " W/mm^2: must be finite and >= 0";
    throw Error(msg.str());
  }
  if (problem.Lights.empty() && problem.UniformIrradiance == 0.0 &&
    !problem.HasInteriorSources())
  {
    throw Error("montecarlo: the problem has no light (no Lights, UniformIrradiance 0 and no "
                "interior source): the Monte Carlo reference launches its photons from the "
                "lights and sources, not from the Irradiance array");
  }
  const bool timed = gates.Count != 0;
  if (timed)
  {
    try
    {
      gates.Validate();
    }
    catch (const Error& e)
    {
      throw Error(std::string("montecarlo: ") + e.what());
    }
  }
  for (std::size_t l = 0; l < problem.Lights.size(); ++l)
  {
    if (problem.Lights[l].Type == LightSource::Kind::Uniform)
    {
      throw Error("montecarlo: light " + std::to_string(l) +
        " is uniform: pass a uniform light as DiffusionProblem::UniformIrradiance");
    }
  }
}

} // namespace

bool MonteCarloSolver::Solve(
  const DiffusionProblem& problem, std::vector<double>& fluence, SolverReport& report)
{
  // ---- Input checks (before any work).
  CheckInputs(*this, problem);
  const TetMesh& mesh = *problem.Mesh;
  const OpticalProperties& material = *problem.Material;
  const int numTets = mesh.GetNumberOfTets();
  const int numPoints = mesh.GetNumberOfPoints();
  const bool timed = Gates_.Count != 0;

  // ---- Set-up: walk structure, per-light irradiance, source tables.
  auto start = Clock::now();
  const Progress progress = [this](double fraction) { return ReportProgress(fraction); };
  const std::vector<double> pointEta =
    BoundaryPointRefractiveIndex(mesh, material.RefractiveIndex);
  LaunchTables tables;
  bool aborted =
    !ReportProgress(0.0) || !PrepareLights(problem, UniformLightSamples_, progress, tables.Lights);
  if (ShareSize_ > 1)
  {
    // An abort on one process is every process's (the same calls on each).
    double any = aborted ? 1.0 : 0.0;
    SumOverShare(&any, 1);
    aborted = any > 0.0;
  }
  if (aborted)
  {
    return false;
  }
  PlaceInteriorSources(problem, tables);
  DetectorMap detectorMap;
  const std::vector<DetectorFootprint> footprints = LocateFootprints(mesh, Detectors_);
  detectorMap.Build(mesh, footprints);
  WalkMesh walk;
  walk.Build(mesh);
  AttachPencilEntries(walk, tables);
  // The shadowed uniform light launches along unoccluded directions only.
  const bool uniformShadowed =
    problem.UniformIrradiance > 0.0 && problem.Shadows && UniformLightSamples_ > 0;
  RayCaster caster;
  const double diag = BoundingBoxDiagonal(mesh);
  if (uniformShadowed)
  {
    caster.Build(mesh.GetPoints(), mesh.GetBoundaryTriangles());
  }
  BuildChannelSources(mesh, tables);
  const double maxFt = MaxUniformTransmittance(material.RefractiveIndex);
  const double setupMs = MillisecondsSince(start);

  // ---- Tracing.
  start = Clock::now();
  const BatchPlan plan =
    MakeBatchPlan(*this, mesh, tables, detectorMap.Count, ShareRank_, ShareSize_);
  const auto sumOverShare = [this](double* values, std::size_t count)
  { SumOverShare(values, count); };
  long long tracedHere = 0;
  std::atomic<long long> done(0);
  std::atomic<bool> stop(false);
  Estimates estimates(plan, footprints, timed ? Gates_.Count : 0);
  std::vector<BatchTally> tallies(plan.Slots);
  BatchSums sums(plan);
  const std::size_t tallyBytes = static_cast<std::size_t>(plan.Slots) *
      (numTets + static_cast<std::size_t>(numPoints) + plan.DetectorItems + plan.GateItems) *
      sizeof(double) +
    (sums.TetSum.size() + 4 * static_cast<std::size_t>(numPoints)) * sizeof(double) +
    (estimates.TetFluence.size() + 4 * estimates.PointFluence.size()) * sizeof(double);

  for (int c = 0; c < NumberOfChannels && !stop; ++c)
  {
    if (!(tables.Sources[c].Power > 0.0))
    {
      continue; // dark channel: everything stays 0
    }
    Tracer tracer;
    tracer.Mesh = &mesh;
    tracer.Walk = &walk;
    tracer.Source = &tables.Sources[c];
    tracer.Lights = &tables.Lights;
    tracer.Interior = &tables.Interior;
    tracer.Detectors = detectorMap.Count > 0 ? &detectorMap : nullptr;
    if (timed)
    {
      tracer.GateStart = Gates_.Start;
      tracer.GateEnd = Gates_.End;
      tracer.GateWidth = Gates_.GetWidth();
      tracer.GateCount = Gates_.Count;
    }
    tracer.Caster = uniformShadowed ? &caster : nullptr;
    tracer.Eta = &material.RefractiveIndex;
    tracer.Anisotropy = Anisotropy_;
    tracer.Weight = tables.Sources[c].Power / static_cast<double>(plan.Photons);
    tracer.RayOffset = 1e-5 * diag; // as ComputeBoundaryIrradiance
    tracer.RayReach = 2.0 * diag;
    tracer.MaxUniformTransmittance = maxFt;
    tracer.Seed = Seed_;
    tracer.Channel = c;
    SetChannelCoefficients(material, c, Anisotropy_, walk);
    sums.Clear();
    TraceBatches(
      tracer, plan, mesh, progress, tallies, sums, estimates.Balances[c], done, stop);
    tracedHere += estimates.Balances[c].Photons;
    if (ShareSize_ > 1)
    {
      AddOverShare(sumOverShare, sums, estimates.Balances[c], stop);
    }
    if (stop)
    {
      break;
    }
    StoreChannelEstimates(c, sums, plan, mesh, Gates_, estimates);
  }
  if (stop)
  {
    return false;
  }
  const double solveMs = MillisecondsSince(start);

  // ---- Outputs.
  std::vector<double> radiance, radianceError;
  ExitanceToRadiance(mesh, pointEta, estimates, radiance, radianceError);
  long long traced = 0;
  for (const PowerBalance& b : estimates.Balances)
  {
    traced += b.Photons;
  }
  Balance_ = estimates.Balances;
  TetFluence_ = std::move(estimates.TetFluence);
  Exitance_ = std::move(estimates.Exitance);
  ExitanceError_ = std::move(estimates.ExitanceError);
  Readings_ = std::move(estimates.Readings);
  ReadingErrors_ = std::move(estimates.ReadingErrors);
  GateReadings_ = std::move(estimates.GateReadings);
  GateReadingErrors_ = std::move(estimates.GateErrors);
  PhotonsTraced_ = traced;
  ThreadsUsed_ = plan.Slots;
  Rate_ = solveMs > 0.0 && plan.Slots > 0 ? tracedHere / (solveMs * 1e-3) / plan.Slots : 0.0;

  report = MakeReport(GetName(), numTets, tallyBytes + walk.Bytes(), tables, setupMs, solveMs);
  report.FluenceStandardError = std::move(estimates.PointFluenceError);
  report.Radiance = std::move(radiance);
  report.RadianceStandardError = std::move(radianceError);
  fluence = std::move(estimates.PointFluence);
  ReportProgress(1.0);
  return true;
}

} // namespace translucency
