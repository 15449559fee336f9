/**
 * @file CollimatedSource.h
 * @brief The extended-source model of a collimated broad beam (issue 19;
 * Documentation/DiffuseOptics.md, "Collimated beams: the extended source").
 *
 * Instead of entering as the boundary irradiance q, the transmitted part of a
 * directional light travels on, unscattered, along the refracted direction
 * and decays as exp(-mu_t' s) (s the path length inside the medium, mu_t' =
 * mu_a + mu_s'); what it loses to scattering is the isotropic volume source
 * mu_s' E_c of the diffusion equation and what it loses to absorption is
 * absorbed directly (Star 1995, "Diffusion theory of light transport", in
 * Welch & van Gemert, Optical-Thermal Response of Laser-Irradiated Tissue,
 * the collimated-plus-diffuse decomposition with the similarity relation
 * g* = 0: the scattered light of the reduced beam is isotropic, so the
 * first-moment source and its boundary term vanish; DiffuseOptics.md derives
 * the general term for our boundary condition). The total fluence rate is
 * phi_d + E_c.
 *
 * Frequency and time domain (ComputeCollimatedFrequencyLoad,
 * ComputeCollimatedTimeLoad): the unscattered beam is a wave (a pulse) that
 * enters at the entry point at phase 0 (at t = 0) and reaches the path
 * length s at t = eta s / c, so its fluence and volume source carry the
 * delay: E_c exp(-i omega eta s / c) modulated, E_c delta(t - eta s / c) for
 * a pulse. This is the unscattered (reduced-intensity) solution of the
 * time-dependent transport equation, (1/c_m d/dt + d/ds + mu_t) I = 0, whose
 * solution is the entering intensity delayed by s / c_m and attenuated by
 * exp(-mu_t s) (Ishimaru 1978, "Wave Propagation and Scattering in Random
 * Media", vol. 1, Academic Press, the time-dependent transport equation; no
 * section cited: the book was not at hand), with the reduced mu_t' of
 * Star's split above; the modulation convention exp(+i omega t) is that of
 * the frequency-domain diffusion equation (Arridge 1999, Inverse Problems
 * 15, R41-R93).
 * Documentation/DiffuseOptics.md, "Collimated beams in the frequency and time
 * domain".
 */
#pragma once

#include "LightSources.h"
#include "OpticalProperties.h"

#include <array>
#include <cstddef>
#include <complex>
#include <cstdint>
#include <memory>
#include <vector>

namespace translucency
{

class TetMesh;

/// How a directional (collimated) light enters the diffusion model.
enum class CollimatedModel
{
  Surface,  ///< as boundary irradiance q (TransCut eq. 2), the default
  Extended, ///< as the volume source mu_s' E_c (CollimatedSource.h)
  /// Extended, with the Robin condition of every boundary term of the solve
  /// from the Fresnel moments (Fresnel::BoundaryRule::Moments) instead of
  /// the fit: the consistent P1 (Marshak) condition. DiffuseOptics.md has
  /// the derivation and the gain against Monte Carlo.
  ExtendedMoments
};

/// True for the models with the volume source (Extended, ExtendedMoments).
inline bool IsExtendedCollimatedModel(CollimatedModel model)
{
  return model != CollimatedModel::Surface;
}

/// The unscattered beam of the directional lights and its source terms.
struct CollimatedSource
{
  /// Collimated fluence rate E_c (W/mm^2), 3 per mesh point (R, G, B).
  std::vector<double> Fluence;
  /// Weak-form load integral of mu_s' E_c phi_i dV (W), 3 per mesh point:
  /// the volume source of the diffuse fluence.
  std::vector<double> Load;
  /// Integral of mu_s' E_c (the sum of Load) and of mu_a E_c over the
  /// object (W per channel): the beam's power scattered into the diffuse
  /// field and absorbed directly.
  std::array<double, NumberOfChannels> Scattered{};
  std::array<double, NumberOfChannels> Absorbed{};
  /// Power of the beams transmitted into the object (W per channel): the
  /// sum over the boundary triangles of (S_f / 3) sum of the corner values
  /// of E cos(theta_i) F_t(theta_i) (ComputeTriangleCornerIrradiance of the
  /// directional lights).
  std::array<double, NumberOfChannels> Entering{};

  /// One directional light's own beam (the frequency and time domains need
  /// its delay; the loads are integrated beam by beam).
  struct Beam
  {
    /// E_c of this beam (W/mm^2), 3 per mesh point; 0 where it does not
    /// arrive.
    std::vector<double> Fluence;
    /// The optical path eta s (mm) from the entry point to the mesh point
    /// along the refracted ray (eta of the entry tet, as mu_t'): the beam
    /// arrives eta s / c after it entered. 1 per mesh point.
    std::vector<double> OpticalPath;
  };
  /// The directional lights' beams, in their order in `lights`.
  std::vector<Beam> Beams;
};

/**
 * The extended source of the directional lights in `lights` (the others are
 * ignored: they stay boundary irradiance).
 *
 * Per mesh point x and light (direction of travel d, irradiance E), a ray
 * from x towards the light (-d; from just inside the surface for a boundary
 * point) finds the entry point: the first boundary triangle hit, at distance
 * t, with outward normal n and cos(theta_i) = n . (-d) > 0. With shadows,
 * the light must reach the entry point (a shadow ray as in
 * ComputeBoundaryIrradiance). The beam is refracted at the entry point
 * (Snell: sin(theta_t) = sin(theta_i) / eta) and the path length to the
 * depth t cos(theta_i) below the entry plane is s = t cos(theta_i) /
 * cos(theta_t) (the local-slab approximation: exact for a flat entry face);
 *   E_c = E cos(theta_i) F_t(theta_i) / cos(theta_t) exp(-mu_t' s),
 * with mu_t', eta of the tet under the entry triangle (the homogeneous
 * approximation along the path).
 *
 * The load integrates mu_s'(tet) E_c phi_i over each tet with E_c
 * interpolated log-linearly between the tet's vertices (exact for one beam
 * through a flat face into a homogeneous medium), linearly where a vertex
 * has E_c = 0, by a composite rule: the tet split L times into 8 by its
 * edge midpoints, 4 points of degree 2 in each sub-tet, L the smallest
 * level (<= 4) at which ln E_c varies by at most 0.5 across a sub-tet.
 * Each beam is integrated on its own (Beams) and the loads are summed:
 * exact per beam where several beams light one tet.
 *
 * Throws translucency::Error on invalid lights or material (sizes,
 * values). OpenMP-parallel over the points.
 *
 * `evaluation`: Fast (the default) evaluates the same rule faster than
 * Reference, the straightforward evaluation kept for the tests (the loads
 * equal to 1e-12; Documentation/DiffuseOptics.md, "What the default costs
 * in a relight").
 */
enum class CollimatedEvaluation
{
  /// The level-1 rule's exponentials factorised (4 exp and 12 sqrt instead
  /// of 32 exp), the logarithms of E_c taken once per point, the exact
  /// integrals of a real tet up to 4 e-folds across from one series
  /// (ExponentialMoments), each beam's rays through a grid of the boundary
  /// triangles binned along its direction (the same hits as RayCaster's),
  /// and the shadow caster of the boundary (and its normals and diagonal)
  /// kept from the last call on the same geometry
  /// (TetMesh::GetGeometryRevision(); one mesh's kept in the process).
  Fast,
  /// Per tet and channel: the logarithms, VisitTet's 4 or 32 direct
  /// exponentials, the exact integrals by the memoised recursion of
  /// ExponentialDividedDifference, and the rays through a RayCaster built
  /// for the call (the evaluation before issue 31's beam work).
  Reference
};
CollimatedSource ComputeCollimatedSource(const TetMesh& mesh, const OpticalProperties& material,
  const std::vector<LightSource>& lights, bool shadows,
  CollimatedEvaluation evaluation = CollimatedEvaluation::Fast);

/**
 * The loads of a beam field (AddCollimatedLoads(): Load, Scattered,
 * Absorbed) kept across calls on one mesh geometry: the load half of
 * CollimatedSourceCache, shared by the distributed beam on each rank's piece
 * (Solvers/Parallel/DistributedCollimatedSource.h). Update() compares the
 * beams' E_c at every point and the tets' mu_a and mu_s' with the last
 * call's: the tets whose mu_a or mu_s' changed or that touch a point whose
 * E_c changed ("dirty") are integrated again, with the tets around their
 * vertices, whose loads are summed again in AddCollimatedLoads' order, so
 * Load equals a fresh AddCollimatedLoads() bit for bit; Scattered and
 * Absorbed are updated by the dirty tets' differences (equal to rounding,
 * ~1e-16 relative per call). More than a quarter of the tets dirty, another
 * geometry (TetMesh::GetGeometryRevision(), the point or tet count), another
 * number of beams or `keep` false: every tet is integrated. Memory: the
 * beams (32 bytes per point and beam), the loads (24 per point), mu_a and
 * mu_s' (48 per tet).
 */
class CollimatedLoadCache
{
public:
  /// out.Load, out.Scattered and out.Absorbed of out.Beams (E_c at every
  /// point of `mesh`) over the tets of `mesh`; `keep` false integrates every
  /// tet (new rays). `material` must be valid for the mesh.
  void Update(const TetMesh& mesh, const OpticalProperties& material, bool keep,
    CollimatedSource& out);
  ///@{
  /// What the last Update() did: "full" (nothing kept: every tet), "loads"
  /// (the dirty tets and their ring, or every tet past a quarter dirty) or
  /// "kept" (nothing dirty: the kept loads); and how many tets it integrated.
  const char* GetLastUpdate() const { return LastUpdate_; }
  long long GetTetsIntegrated() const { return TetsIntegrated_; }
  ///@}
  /// The beams of the last Update() (empty before).
  const std::vector<CollimatedSource::Beam>& GetBeams() const { return Beams_; }
  /// Forget everything kept.
  void Clear();
  /// Bytes held by what is kept.
  std::size_t GetMemoryBytes() const;

private:
  /// Update(): Load, Scattered and Absorbed from the kept ones, the `dirty`
  /// tets (and those around their vertices) integrated again.
  void UpdateLoads(const TetMesh& mesh, const OpticalProperties& material,
    const std::vector<int>& dirty, CollimatedSource& out);
  bool Valid_ = false;
  std::uint64_t Revision_ = 0;
  int Points_ = 0, Tets_ = 0;
  std::vector<double> MuA_, MuS_;
  std::vector<CollimatedSource::Beam> Beams_;
  std::vector<double> Load_;
  std::array<double, NumberOfChannels> Scattered_{}, Absorbed_{};
  const char* LastUpdate_ = "full";
  long long TetsIntegrated_ = 0;
};

/**
 * ComputeCollimatedSource() (Fast) kept across the calls of an interactive
 * session (issue 31: a paint stroke must not cost a whole beam set-up).
 * What is kept from the last call: each beam's entry triangle per mesh point
 * (the rays: they depend on the geometry, the beams' directions and the
 * shadow flag only, not on the material), the result, and the tets' mu_a
 * and mu_s'. A call with the same mesh geometry (TetMesh::GetGeometryRevision()),
 * directions and shadow flag casts no ray:
 *  - E_c is evaluated again from the kept entry triangles only when the
 *    material under the boundary or a beam's power changed (a few ms);
 *  - the tets whose mu_a or mu_s' changed or that touch a point whose E_c
 *    changed ("dirty") are integrated again, with the tets around their
 *    vertices, whose loads are summed again in the full computation's
 *    order: Load and Fluence equal ComputeCollimatedSource()'s bit for bit;
 *    Scattered and Absorbed are updated by the dirty tets' differences
 *    (equal to rounding, ~1e-16 relative per call);
 *  - more than a quarter of the tets dirty: the loads are integrated anew.
 * Another geometry, direction or shadow flag computes everything (and keeps
 * it). Memory: 4 bytes per point and beam, 48 per tet, the last result.
 */
class CollimatedSourceCache
{
public:
  CollimatedSourceCache();
  ~CollimatedSourceCache();
  CollimatedSourceCache(const CollimatedSourceCache&) = delete;
  CollimatedSourceCache& operator=(const CollimatedSourceCache&) = delete;

  /// ComputeCollimatedSource(mesh, material, lights, shadows), re-using
  /// what is kept (see the class comment). Same errors.
  CollimatedSource Compute(const TetMesh& mesh, const OpticalProperties& material,
    const std::vector<LightSource>& lights, bool shadows);

  ///@{
  /// What the last Compute() did: "full" (rays cast, every tet integrated),
  /// "loads" (the kept rays, the tets in GetTetsIntegrated() integrated
  /// again) or "kept" (nothing changed: the kept result); and how many tets
  /// it integrated.
  const char* GetLastUpdate() const { return LastUpdate_; }
  long long GetTetsIntegrated() const { return TetsIntegrated_; }
  ///@}

  /// Forget everything kept.
  void Clear();

  /// Bytes held by what is kept.
  std::size_t GetMemoryBytes() const;

private:
  struct Internals;
  std::unique_ptr<Internals> I_;
  const char* LastUpdate_ = "full";
  long long TetsIntegrated_ = 0;
};

/// The boundary surface a beam enters through (ComputeCollimatedBeamAtPoints):
/// outward triangles on their points and the optical properties of the tet
/// under each triangle (the homogeneous approximation along the path).
struct CollimatedEntrySurface
{
  const std::vector<double>* Points = nullptr; ///< 3 coordinates per point (mm)
  const std::vector<int>* Triangles = nullptr; ///< 3 point indices each, (p1 - p0) x (p2 - p0) outward
  std::vector<double> Eta;        ///< refractive index of the tet under each triangle
  std::vector<double> Extinction; ///< mu_a + mu_s' of that tet, 3 per triangle (1/mm)
  double Diagonal = 0.0;          ///< bounding-box diagonal of every mesh point (mm)
};

/**
 * ComputeCollimatedSource()'s beam field (Fluence and Beams, E_c and the
 * optical path of each directional light in `beams`) at chosen points,
 * each ray cast against `surface`: the mesh's own boundary in one process,
 * the all-gathered physical boundary of a distributed mesh
 * (Solvers/Parallel/DistributedCollimatedSource.h) on each MPI rank. The
 * same arithmetic per point whichever points are asked for.
 * @param points 3 coordinates per query point (mm)
 * @param onBoundary per query point: on the boundary surface (its ray then
 *   starts just inside, along -normal)
 * @param normals 3 per query point: the outward unit point normal (read on
 *   the boundary only)
 * @param out Fluence and Beams are sized to the query points and filled;
 *   Load and the power sums are left alone (AddCollimatedLoads()).
 * `beams` must be directional and valid (ValidateLight()).
 */
void ComputeCollimatedBeamAtPoints(const CollimatedEntrySurface& surface,
  const std::vector<LightSource>& beams, bool shadows, const std::vector<double>& points,
  const std::vector<char>& onBoundary, const std::vector<double>& normals, CollimatedSource& out);

/**
 * The two halves of ComputeCollimatedBeamAtPoints() (Fast), for a caller
 * that keeps the rays (CollimatedSourceCache, the distributed beam): per
 * beam and query point, the index of the triangle of `surface` through which
 * the beam reaches the point, or -1 (no entry, or the entry shadowed). It
 * depends on the surface's geometry, the beams' directions, the shadow flag
 * and the points, not on the material or the powers. Arguments as
 * ComputeCollimatedBeamAtPoints().
 */
std::vector<std::vector<int>> CastCollimatedBeamEntries(const CollimatedEntrySurface& surface,
  const std::vector<LightSource>& beams, bool shadows, const std::vector<double>& points,
  const std::vector<char>& onBoundary, const std::vector<double>& normals);

/**
 * The optical half: E_c of every beam at the query points and the optical
 * path, from the entry triangles of CastCollimatedBeamEntries() and the
 * material under them (surface.Eta, surface.Extinction) and the beams'
 * powers. out.Fluence and out.Beams must be sized to the points and zeroed;
 * CastCollimatedBeamEntries() then this equal ComputeCollimatedBeamAtPoints()
 * bit for bit.
 */
void EvaluateCollimatedBeamField(const CollimatedEntrySurface& surface,
  const std::vector<LightSource>& beams, const std::vector<double>& points,
  const std::vector<std::vector<int>>& entries, CollimatedSource& out);

/**
 * ComputeCollimatedSource()'s load: the integral of mu_s' E_c phi_i over each
 * tet of `mesh` per beam of out.Beams (3 per mesh point), added to out.Load
 * (sized to the mesh's points if it is not), out.Scattered and out.Absorbed.
 * On a rank's piece of a distributed mesh (its own tets), the sums over the
 * ranks are the whole mesh's.
 */
void AddCollimatedLoads(const TetMesh& mesh, const OpticalProperties& material, CollimatedSource& out);

/**
 * Frequency domain: the beams of `source` modulated at omega with phase 0 at
 * their entry points (Documentation/DiffuseOptics.md, "Collimated beams in
 * the frequency and time domain"). Per point, the complex collimated fluence
 *   E_c~(x) = sum over beams E_b(x) exp(-i k eta s_b(x)),  k = omega / c (rad/mm),
 * and the complex load, the integral of mu_s' E_c~ phi_i dV (W), per tet and
 * beam by ComputeCollimatedSource's rule with the exponent ln E_b - i k
 * eta s_b interpolated linearly (exact for one beam through a flat face
 * into a homogeneous medium); the level also keeps k eta s from varying by
 * more than 0.5 rad per sub-tet. k = 0 gives ComputeCollimatedSource's
 * Load and Fluence exactly.
 * @param wavenumber k = omega / c in rad per mm of optical path (>= 0)
 * @param load, fluence 3 per mesh point (R, G, B)
 */
void ComputeCollimatedFrequencyLoad(const TetMesh& mesh, const OpticalProperties& material,
  const CollimatedSource& source, double wavenumber, std::vector<std::complex<double>>& load,
  std::vector<std::complex<double>>& fluence);

/// One piece of the time-domain volume source: Load (W x ns = J per J of
/// pulse, per channel) enters the vertex Point at the time Times[Time].
struct CollimatedDeposit
{
  int Time = 0;
  int Point = 0;
  std::array<double, NumberOfChannels> Load{};
};

/**
 * Time domain: the beams of `source` as pulses entering at t = 0: the
 * volume source mu_s' E_b(x) delta(t - eta s_b(x) / c). Its space integral
 * is taken with exactly ComputeCollimatedSource's quadrature points and
 * weights; the pulse of each quadrature point, at its arrival time tau (ns;
 * interpolated linearly from the tet's vertices), is split linearly
 * between the two neighbouring times of `times` (ascending, times[0] = 0,
 * ns): (t1 - tau) / (t1 - t0) at t0 and the rest at t1, which keeps the
 * total and the mean arrival time (a hat-function projection in time).
 * Arrivals after the last time are left out (they come after the run).
 * Returned sorted by (Time, Point), one deposit per pair; when the times
 * reach past every arrival, the loads sum to ComputeCollimatedSource's Load.
 */
std::vector<CollimatedDeposit> ComputeCollimatedTimeLoad(const TetMesh& mesh,
  const OpticalProperties& material, const CollimatedSource& source,
  const std::vector<double>& times);

/// The lights without the directional ones (what stays boundary irradiance
/// under the extended model).
std::vector<LightSource> NonCollimatedLights(const std::vector<LightSource>& lights);

} // namespace translucency
