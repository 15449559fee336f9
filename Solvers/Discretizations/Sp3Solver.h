/**
 * @file Sp3Solver.h
 * @brief The simplified spherical harmonics equations of order 3 (SP3;
 * Klose & Larsen 2006, J. Comput. Phys. 220:441-470) on the tet mesh: P1
 * finite elements for the two composite moments phi_1, phi_2 at the mesh
 * vertices, with anisotropic scattering (OpticalProperties::Anisotropy) and
 * the partly reflecting (Fresnel) Marshak boundary conditions.
 * Documentation/Solvers.md ("SP3") has the equations and the measured
 * accuracy against Monte Carlo.
 */
#pragma once

#include "DiffusionSolver.h"
#include "DiffusionSystem.h"
#include "LinearSolver.h"
#include "Radiance.h"
#include "TetGeometry.h"

#include <array>
#include <complex>
#include <cstdint>
#include <memory>
#include <vector>

namespace translucency
{

/**
 * The boundary conditions of the SP3 equations at a boundary with relative
 * refractive index eta (medium / outside), n the outward normal
 * (Klose & Larsen 2006, the SP3 case of their Marshak conditions):
 *
 *   (1/2 + A1) phi_1 + (1 + B1)/(3 mu_a1) n.grad phi_1
 *       = (1/8 + C1) phi_2 + (D1 / mu_a3) n.grad phi_2 + 2 q,
 *   (7/24 + A2) phi_2 + (1 + B2)/(7 mu_a3) n.grad phi_2
 *       = (1/8 + C2) phi_1 + (D2 / mu_a1) n.grad phi_1 - q / 2,
 *
 * with, from the half-range moments r_m = int_0^1 R(mu) mu^m dmu of the
 * Fresnel reflectance (Fresnel::ReflectanceHalfRangeMoments):
 *   A1 = -r1,  B1 = 3 r2,  C1 = C2 = (5 r3 - 3 r1) / 2,  D1 = D2 = (3 r2 - 5 r4) / 2,
 *   A2 = -9 r1 / 4 + 15 r3 / 2 - 25 r5 / 4,  B2 = 63 r2 / 4 - 105 r4 / 2 + 175 r6 / 4.
 * Derived here from the Marshak conditions int_0^1 (psi(mu) - R(mu)
 * psi(-mu) - S(mu)) P_k(mu) dmu = 0, k = 1, 3, for the P3 radiance, with the
 * transmitted boundary source S uniform over the inward hemisphere
 * (S = q / pi, q the transmitted irradiance DiffusionProblem::Irradiance,
 * as in the diffusion solvers' Robin condition). At eta = 1 all eight are 0.
 *
 * Solved for the currents J_1 = -(1/(3 mu_a1)) n.grad phi_1 and
 * J_2 = -(1/(7 mu_a3)) n.grad phi_2 (what the weak form needs):
 *   J_1 = F11 phi_1 + F12 phi_2 + S1 q,   J_2 = F21 phi_1 + F22 phi_2 + S2 q
 * (at eta = 1: 1/2, -1/8, -2 and -1/8, 7/24, 1/2). F12 != F21 when
 * eta != 1 (e.g. 0.0866 and 0.0905 at eta = 1.3), so the SP3 system is not
 * symmetric then.
 *
 * The exitance (power per area leaving through the boundary, W/mm^2) is
 * J_out = E1 phi_1 + E2 phi_2 + E3 q: the transmitted part of the outgoing
 * P3 radiance, 2 pi int_0^1 (1 - R(mu)) psi(-mu) mu dmu.
 */
struct Sp3BoundaryCoefficients
{
  double A1 = 0, B1 = 0, C1 = 0, D1 = 0, A2 = 0, B2 = 0, C2 = 0, D2 = 0;
  double F11 = 0.5, F12 = -0.125, F21 = -0.125, F22 = 7.0 / 24.0, S1 = -2.0, S2 = 0.5;
  double E1 = 0, E2 = 0, E3 = 0;

  /// The coefficients for relative index eta (finite, > 0).
  static Sp3BoundaryCoefficients Compute(double eta);
};

/**
 * The radiance leaving the surface of an SP3 solution (W/mm^2/sr): the
 * outgoing half of the P3 radiance inside, L(-mu) = (1/(4 pi)) [phi_0 +
 * 3 J_1 mu + (5/3) Phi_2 P_2(mu) + 7 J_2 P_3(mu)] (mu the internal cosine
 * with the outward normal, Snell's partner of cosOut; phi_0 = Phi_1 -
 * (2/3) Phi_2, J_1, J_2 the currents of the boundary conditions `k`),
 * times the Fresnel transmittance 1 - R, divided by eta^2 (the n^2 law)
 * unless `readout` is RadianceReadout::Paper. The exitance (k.E1 Phi_1 +
 * k.E2 Phi_2 + k.E3 q) is its integral over the outgoing hemisphere,
 * 2 pi int L cosOut dcosOut. SP3's counterpart of OutgoingRadiance (TransCut
 * eq. 3); clamped below at 0, 0 for cosOut <= 0.
 * @param phi1, phi2 the composite moments at the point (W/mm^2)
 * @param q the boundary irradiance at the point (W/mm^2)
 * @param eta the refractive index at the point (k is Compute(eta))
 */
double Sp3OutgoingRadiance(const Sp3BoundaryCoefficients& k, double eta, double phi1, double phi2,
  double q, double cosOut, RadianceReadout readout = RadianceReadout::EnergyConserving);

/**
 * Sp3OutgoingRadiance at every boundary point of the mesh, in the order of
 * mesh.GetBoundaryPoints() (3 values, R, G, B), as BoundaryRadiance (whose
 * arguments these are, with the composite moments Phi_1, Phi_2 of an SP3
 * solve, 3 per mesh point, in place of the fluence): each point seen
 * along its normal, or from `viewPoint`. Throws translucency::Error on
 * wrong array sizes or a non-finite result.
 */
std::vector<double> Sp3BoundaryRadiance(const TetMesh& mesh, const std::vector<double>& phi1,
  const std::vector<double>& phi2, const std::vector<double>& irradiance,
  const std::vector<double>& pointEta, const double* viewPoint,
  RadianceReadout readout = RadianceReadout::EnergyConserving);

class Sources;
struct OpticalProperties;

/**
 * The isotropic source Q of the SP3 equations (weak-form load, W, 3 per mesh
 * point) from interior sources: point sources as given; a pencil beam by its
 * first-collision source along the refracted beam, mu_s' exp(-mu_t' s) per
 * mm of path s times the transmitted power (1 - R_sp) P (LocatePencilEntry),
 * mu_s', mu_t' = mu_a + mu_s' of the tet under the entry point (the
 * homogeneous approximation of the extended collimated model, whose
 * similarity rule g* = 0 this is; exact for isotropic scattering, g = 0:
 * then it is the transport equation's own first-collision source), as point
 * sources at the midpoints of segments of 0.1 / mu_t' (max over channels)
 * carrying each segment's exact power, up to 12 / mu_t' (min) or where the
 * beam leaves the object. The unscattered beam itself (a line singularity)
 * is not in the fluence; its direct absorption, the fraction mu_a / mu_t',
 * is not injected. Throws translucency::Error as Sources::Place does.
 */
std::vector<double> ComputeSp3SourceLoad(
  const TetMesh& mesh, const OpticalProperties& material, const Sources& sources);

/**
 * The same source modulated at omega (frequency domain): the point sources
 * at phase 0, each pencil-beam segment with the beam's delay, power
 * P exp(-i k eta s) (k = omega / c in rad per mm, eta s the optical path
 * from the entry point, eta of the tet under it; as
 * ComputeCollimatedFrequencyLoad does for the extended model). Returns the
 * real part; `imaginary` gets the imaginary part (3 per point; empty when
 * k = 0, where this is the function above).
 */
std::vector<double> ComputeSp3SourceLoad(const TetMesh& mesh, const OpticalProperties& material,
  const Sources& sources, double wavenumber, std::vector<double>& imaginary);

/**
 * The SP3 solver (registry name "sp3"). Unknowns: phi_1 = phi_0 + 2 phi_2
 * and phi_2 := 3 phi_2 (the composite moments of Klose & Larsen) at the mesh
 * vertices, 2 N per channel; the fluence is phi_0 = phi_1 - (2/3) phi_2.
 *
 * Equations (per channel; mu_an = mu_a + mu_s (1 - g^n), mu_s =
 * sigma_s' / (1 - g), so mu_a1 = mu_a + sigma_s', mu_a2 = mu_a + sigma_s'
 * (1 + g), mu_a3 = mu_a + sigma_s' (1 + g + g^2)):
 *   -div(1/(3 mu_a1) grad phi_1) + mu_a phi_1 - (2/3) mu_a phi_2 = Q,
 *   -div(1/(7 mu_a3) grad phi_2) + ((4/9) mu_a + (5/9) mu_a2) phi_2
 *       - (2/3) mu_a phi_1 = -(2/3) Q,
 * with Q the isotropic interior sources (point sources, pencil beams by
 * their equivalent point source: InteriorSources.h) and the boundary
 * conditions of Sp3BoundaryCoefficients (q enters there).
 *
 * Discretisation: consistent P1 Galerkin on the tets (exact element
 * stiffness, consistent mass, consistent boundary mass and load per boundary
 * triangle with the eta of its tet), the same integrals as FiniteElement.
 *
 * Linear solve: the 2 x 2 block system is symmetric in its interior part
 * (and positive definite: the mass block's determinant is (5/9) mu_a mu_a2)
 * but its Fresnel boundary coupling is not (F12 != F21), so it is solved by
 * BiCGSTAB (or restarted GMRES: SetKrylovMethod), preconditioned by the
 * block diagonal: Jacobi ("jacobi", the
 * default below VertexDiffusionSolver::LargeSystemUnknowns vertices) or one
 * multigrid-agg cycle on each diagonal block ("multigrid-agg", the default
 * from there on; the two cycles share one aggregation hierarchy:
 * AggregationMultigridSolver::SetupSharedHierarchy), the three channels
 * together; warm start from the last solution on the same mesh. A
 * continuous-wave solve on the same mesh with an equal material (a
 * relight, other sources) rebuilds only the right-hand sides and keeps the
 * blocks and the cycles' set-up (SolverReport::Assembly "right-hand side",
 * LinearSetup "kept"; the blocks depend on the mesh, the material and
 * omega only, and the kept material is compared entry by entry). SetLinearSolver: "" (by size), or the names
 * of its registry entry (DiffusionSolverTraits::LinearSolvers, what the
 * filter and the plugin offer): "bicgstab" (the diagonal; the short
 * "jacobi" too) or "multigrid-agg", mapped by their LinearSolverTraits;
 * others are an error.
 *
 * Sources: the boundary irradiance q (diffusive, in the boundary
 * conditions); point sources as isotropic delta sources Q; pencil beams by
 * their first-collision source (ComputeSp3SourceLoad); the extended
 * collimated models (CollimatedSource.h: the reduced beam's volume source
 * mu_s' E_c as Q, E_c added to the fluence) with either boundary rule.
 *
 * Frequency domain (SolveFrequencyDomain, registry trait SupportsFrequency):
 * every mu_an gains i omega eta / c (the transport equation's (eta / c)
 * d/dt), so the diffusion coefficients 1/(3 mu_a1), 1/(7 mu_a3) and the
 * mass coefficients become complex; the boundary conditions (in the
 * currents J_1, J_2) do not change. The complex 2 x 2 block system is
 * solved in its real form [[A, -B], [B, A]] by the same BiCGSTAB with the
 * same block-diagonal preconditioner (built on the real part A) applied to
 * the real and imaginary parts; no warm start. No time domain (the
 * registry's traits; the filter refuses).
 */
class Sp3Solver : public DiffusionSolver
{
public:
  Sp3Solver();
  ~Sp3Solver() override;

  std::string GetName() const override { return "sp3"; }
  /// "anisotropy": g for every tet and channel when the material carries
  /// none (OpticalProperties::Anisotropy, which wins when set); default 0.
  void SetOptions(const SolverOptions& options) override
  {
    options.ReadNumber(GetName(), DiffusionOption::Anisotropy, -1.0,
      "the anisotropy g must be in (-1, 1)", Anisotropy_);
  }
  bool Solve(const DiffusionProblem& problem, std::vector<double>& fluence,
    SolverReport& report) override;
  void Reset() override;

  /**
   * Frequency domain: the complex fluence Phi = phi_1 - (2/3) phi_2 (3 per
   * mesh point, W/mm^2 per W of modulation amplitude; arg < 0: it lags) of
   * the sources and the boundary irradiance modulated at `frequency` Hz with
   * phase 0 (the class comment has the equations). Pencil beams and the
   * extended collimated models carry the beam's own delay exp(-i omega eta
   * s / c). `frequency` finite and > 0, else translucency::Error; refused
   * too when the mesh cannot resolve the diffusion wave
   * (CheckFrequencyResolution). Afterwards GetExitance() holds the
   * amplitude of the exitance and GetComplexExitance() the complex value;
   * GetPhi1/GetPhi2 the real parts. Returns false if the progress callback
   * aborted.
   */
  bool SolveFrequencyDomain(const DiffusionProblem& problem, double frequency,
    std::vector<std::complex<double>>& fluence, SolverReport& report) override;

  /// The composite moments of the last Solve, 3 values (R, G, B) per mesh
  /// point each (W/mm^2).
  const std::vector<double>& GetPhi1() const { return Phi1_; }
  const std::vector<double>& GetPhi2() const { return Phi2_; }
  /// The exitance of the last Solve, 3 values per mesh point (W/mm^2; 0 at
  /// interior points): Sp3BoundaryCoefficients E1 phi_1 + E2 phi_2 + E3 q
  /// with the area-weighted mean eta of the boundary triangles at the point.
  const std::vector<double>& GetExitance() const { return Exitance_; }
  /// The complex exitance of the last SolveFrequencyDomain (3 per point,
  /// W/mm^2 per W of modulation; 0 at interior points); empty after a
  /// continuous-wave Solve.
  const std::vector<std::complex<double>>& GetComplexExitance() const
  {
    return ComplexExitance_;
  }

  /**
   * An additional right-hand side of the weak form (W): load1 and load2
   * hold 3 values (R, G, B) per mesh point for the phi_1 and the phi_2
   * equation, int f_k beta_i dV + int g_k beta_i dS for volume sources f_k
   * and boundary-current data g_k that the problem's q and interior sources
   * cannot express (manufactured solutions). Empty vectors (the default) =
   * none; kept for every following Solve until changed; a size other than
   * 3 per point is a translucency::Error at Solve.
   */
  void SetAdditionalLoad(std::vector<double> load1, std::vector<double> load2)
  {
    AdditionalLoad1_ = std::move(load1);
    AdditionalLoad2_ = std::move(load2);
  }

  /// The power the interior sources of the last Solve injected into the
  /// SP3 field (W per channel; the sum of ComputeSp3SourceLoad). The
  /// balance: int mu_a phi_0 + int_surface GetExitance() = int_surface q +
  /// this (+ the extended model's scattered beam power), to the solver's
  /// tolerance (P1 integrals; uniform eta on the surface).
  const std::array<double, NumberOfChannels>& GetSourcePower() const { return SourcePower_; }

  /// OpenMP threads for assembly and solve (0 = OpenMP default). Default 0.
  void SetNumberOfThreads(int n) { NumberOfThreads_ = n; }

  /**
   * The Krylov method of the block system: "bicgstab" (two block products
   * and two preconditioner applications per iteration), "gmres" (restarted
   * flexible GMRES, one of each per iteration but an orthogonalisation
   * against the whole basis), or "" (the default: bicgstab, the faster in
   * the bench; Solvers.md, SP3 "Cost", has the measurements).
   * Case-insensitive; anything else is a translucency::Error. The report's
   * LinearSolver names the method used ("bicgstab-block-multigrid-agg",
   * "gmres-block-jacobi", ...).
   */
  void SetKrylovMethod(const std::string& name);
  const std::string& GetKrylovMethod() const { return Krylov_; }
  /// GMRES's restart length m (1 to 1000, default 30; vectors are allocated
  /// as a cycle needs them: at most 2 m + 1 of 2 N x 3 values).
  void SetGmresRestart(int m);
  int GetGmresRestart() const { return GmresRestart_; }

private:
  double Anisotropy_ = 0.0; ///< SetOptions' g (used when the material has none)
  struct Blocks;
  /// Validation and the option's anisotropy (into `withAnisotropy`); a new
  /// mesh resets the warm start.
  DiffusionProblem PrepareProblem(const DiffusionProblem& given, OpticalProperties& withAnisotropy);
  std::string ChoosePreconditioner(const TetMesh& mesh) const;
  std::string ChooseKrylov(const std::string& preconditioner) const;
  void SizeBlocks(const TetMesh& mesh, bool complex);
  /// The blocks for angular frequency omega (rad/s; 0: continuous wave,
  /// real) with the interior sources' load (real and imaginary parts).
  /// Returns true for a full assembly, false when only the right-hand sides
  /// were rebuilt (continuous wave, the same mesh and an equal material as
  /// the last continuous-wave assembly: the blocks are the same bits).
  bool Assemble(const DiffusionProblem& problem, const std::vector<double>& sourceLoad,
    const std::vector<double>& imaginaryLoad, double omega);
  /// The right-hand sides' boundary loads alone, in the full assembly's
  /// order (the same bits), on the kept blocks.
  void AssembleRightHandSides(const DiffusionProblem& problem,
    const std::vector<Sp3BoundaryCoefficients>& coefficients, const std::vector<int>& etaIndex);
  void AddLoads(int numPoints, const std::vector<double>& sourceLoad,
    const std::vector<double>& imaginaryLoad);
  /// The block preconditioner's set-up; returns what was done
  /// (SolverReport::LinearSetup): "rebuilt" (the aggregation hierarchy,
  /// shared by the two cycles, and the values), "values" (of a block whose
  /// values changed, or Jacobi's diagonal) or "kept" (a relight: the blocks
  /// did not change).
  const char* SetUpPreconditioner(const TetMesh& mesh, const std::string& preconditioner);
  /// BiCGSTAB on the assembled blocks from `x` (resized and zeroed when its
  /// size does not fit: 2 N x 3, or 4 N x 3 in the frequency domain).
  bool SolveBlocks(const TetMesh& mesh, const std::string& preconditioner, std::vector<double>& x,
    SolverReport& report);
  void ComputeExitance(const DiffusionProblem& problem, const std::vector<double>& imaginaryPhi1,
    const std::vector<double>& imaginaryPhi2);
  void FillReport(const TetMesh& mesh, SolverReport& report) const;

  std::unique_ptr<Blocks> Blocks_;
  int NumberOfThreads_ = 0;
  std::string Krylov_;
  int GmresRestart_ = 30;
  std::vector<double> Phi1_, Phi2_, Exitance_;
  std::vector<std::complex<double>> ComplexExitance_;
  std::vector<double> AdditionalLoad1_, AdditionalLoad2_;
  std::array<double, NumberOfChannels> SourcePower_{};
  std::vector<double> X_; ///< the last solution, 2 N x 3 interleaved (warm start)
  const TetMesh* LastMesh_ = nullptr;
  int LastPoints_ = -1;
  int LastTets_ = -1;
  std::uint64_t LastRevision_ = 0;
  TetGeometryCache GeometryCache_;
  std::vector<int> TriangleHead_, TriangleNext_;
};

} // namespace translucency
