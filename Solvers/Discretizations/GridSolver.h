/**
 * @file GridSolver.h
 * @brief Regular-grid finite differences (Polygrid, eq. 8-9, Sec. 5.3; the
 * "grid" solver of Documentation/Solvers.md): a voxel grid of spacing h
 * embedded automatically in the tetrahedral mesh, boundary nodes on the
 * surface, Stam's 7-point stencil, BiCGSTAB or coloured relaxation, optional
 * coarse-to-fine initialisation.
 */
#pragma once

#include "ResourceLimits.h"

#include "DiffusionSolver.h"
#include "DiffusionSystem.h"
#include "LinearSolver.h"
#include "RayCaster.h"
#include "TetLocator.h"

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace translucency
{

/**
 * One grid level (public so tests and tools can inspect it; owned by
 * GridSolver). Interior unknowns first, then boundary nodes.
 */
struct GridLevel
{
  double Spacing = 0.0;           ///< h (mm)
  double Origin[3] = { 0, 0, 0 }; ///< node (0, 0, 0) (mm)
  int Dims[3] = { 0, 0, 0 };      ///< nodes along x, y, z
  /// Per grid node (x fastest): interior unknown id, or -1 (outside).
  std::vector<int> NodeUnknown;
  std::vector<int> InteriorGrid; ///< grid linear index of each interior node
  std::vector<int> InteriorTet;  ///< containing tet of each interior node
  /// Boundary nodes of interior node u: [BoundaryOffsets[u], BoundaryOffsets[u+1]).
  std::vector<int> BoundaryOffsets;
  struct BoundaryNode
  {
    int Interior = -1;     ///< interior node of the link
    int Direction = 0;     ///< 0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z
    double Distance = 0.0; ///< link length d (mm), clamped to [0.1 h, h]
    double Cosine = 1.0;   ///< |e . n| of the link and the triangle normal
    int Triangle = -1;     ///< hit boundary triangle
    double Weights[3] = { 1.0 / 3, 1.0 / 3, 1.0 / 3 }; ///< barycentric on it
    /// The normal derivative is (phi_b - phi_p) / Probe, phi_p the value at
    /// the probe point x_b - Probe n: sum_k ProbeWeights[k] phi(ProbeNodes[k])
    /// for k < ProbeCount (1: the interior node of the link at the normal
    /// distance delta = d |e . n|; 8: trilinear; 4: linear in a Kuhn tet of
    /// the cell; nodes sorted by id).
    double Probe = 0.0; ///< mm
    int ProbeCount = 1;
    int ProbeNodes[8] = { -1, -1, -1, -1, -1, -1, -1, -1 };
    double ProbeWeights[8] = { 1, 0, 0, 0, 0, 0, 0, 0 };
  };
  std::vector<BoundaryNode> Boundary;
  /// 6 per interior node, by direction: unknown id of the neighbour.
  std::vector<int> Neighbours;
  /// 7 per interior node: position in the row of direction 0..5, then the diagonal.
  std::vector<std::uint8_t> Slots;
  /// Relaxation colours: interior nodes of even i + j + k, of odd i + j + k,
  /// then boundary nodes (no two nodes of one colour are coupled).
  std::vector<int> Colours[3];
  /// Per channel: interior mu_a (1/mm) and kappa (mm); boundary kappa (mm)
  /// and q (W/mm^2).
  std::array<std::vector<double>, NumberOfChannels> Mu, Kappa, BoundaryKappa, BoundarySource;
  std::vector<double> BoundaryRobin; ///< Probe / (2A) per boundary node (mm)
  std::vector<double> BoundaryScale; ///< 4 / (1 - Fdr) per boundary node
  DiffusionSystem System;
  std::array<Eigen::VectorXd, NumberOfChannels> Solution;

  int NumberOfInterior() const { return static_cast<int>(InteriorGrid.size()); }
  int NumberOfBoundary() const { return static_cast<int>(Boundary.size()); }
  int NumberOfUnknowns() const { return NumberOfInterior() + NumberOfBoundary(); }
  void InteriorIndex(int u, int ijk[3]) const
  {
    const int g = InteriorGrid[u];
    ijk[0] = g % Dims[0];
    ijk[1] = (g / Dims[0]) % Dims[1];
    ijk[2] = g / (Dims[0] * Dims[1]);
  }
  /// Position (mm) of unknown u (interior, or boundary node u - interior count).
  void Position(int u, double x[3]) const;
  /// Extents (mm) along x, y, z of the control volume of interior node u:
  /// (h+ + h-) / 2 per axis, h+- the distance to the neighbour (h, or the
  /// link length of a boundary node). Its product is the volume an interior
  /// source's power is divided by.
  void ControlExtents(int u, double extent[3]) const;
  /// Bytes held by the arrays of this level.
  std::size_t MemoryBytes() const;
};

/**
 * The regular-grid solver ("grid"). The paper builds a polygrid by hand
 * (a polycube, Sec. 5.1); here the grid is embedded in the tet mesh
 * automatically.
 *
 * Grid: nodes x = o + (i, j, k) h over the bounding box of the tets, with
 * n_d = ceil(L_d / h) nodes along axis d (L_d the box extent) and the block of
 * nodes centred in the box (a box of extent n h gets nodes at h/2 from its
 * faces). Interior nodes are the grid nodes inside a tet (TetLocator; the
 * lowest tet id on shared faces); they take mu_a and kappa from that tet.
 * For every interior node and each of its 6 axis neighbours that is not
 * interior, a boundary node is placed on the surface on the link between
 * them: the first crossing of the mesh boundary triangles by the ray from
 * the node towards the neighbour (RayCaster). An interior node near an edge
 * or corner of the object has several boundary nodes, one per outside link.
 * A link shorter than 0.1 h is lengthened to 0.1 h (the boundary node then
 * sits up to 0.1 h outside the surface).
 *
 * Interior rows (3 channels): the conservative 7-point scheme with the
 * neighbour distances h+ and h- of each axis (h, or the link length d of a
 * boundary node; polygrid eq. 9 with the Appendix B weights, which for
 * axis-aligned neighbours are w = 2 / (h+- (h+ + h-))) and the harmonic mean
 * of the two nodes' kappa on each link:
 *   sum_axes sum_+- 2 kappa_+- (phi_+- - phi_i) / (h_+- (h_+ + h_-)) - mu_a phi_i = 0,
 * multiplied by h^2 (for d = h everywhere this is Stam's eq. 8 in flux form).
 *
 * Boundary rows: polygrid eq. 9, phi_b + 2 A kappa_b dphi/dn = 4 q_b / (1 - Fdr),
 * with kappa_b, A and Fdr of the tet owning the hit triangle, q_b
 * interpolated linearly (barycentric) on that triangle from the mesh point
 * irradiance, and dphi/dn = (phi_b - phi_p) / l, phi_p the fluence at the
 * probe point x_b - l n (n the triangle's outward unit normal):
 *  - on faces normal to the link (|e . n| = 1): phi_p = phi_i, l = d, the
 *    paper's equation exactly;
 *  - elsewhere (slanted faces): l = h, 1.5 h, ... 3 h, then 0.75 h, 0.5 h,
 *    the first depth at which the grid cell around x_b - l n has its 8
 *    corners inside (trilinear phi_p) or, failing that, one of the 4 Kuhn
 *    tets of that cell (linear phi_p). Linear interpolation keeps the row
 *    first-order consistent; the paper's (phi_b - phi_i) / delta with the
 *    link not along the normal would add the tangential gradient times
 *    tan(angle), an error that does not shrink with h;
 *  - where no probe fits (within about h of sharp edges not aligned with the
 *    grid, or parts thinner than ~h): phi_p = phi_i and l = delta = d |e . n|,
 *    the paper's equation with the normal distance (inconsistent there).
 * The row is multiplied by l / (2A):
 *   (l/(2A) + kappa_b) phi_b - kappa_b phi_p = l/(2A) 4 q_b / (1 - Fdr).
 * Unknowns: interior nodes in grid order (x fastest), then boundary nodes.
 * The matrix is an M-matrix (probe weights are >= 0), non-symmetric.
 *
 * Interior sources (DiffusionProblem::InteriorSources, continuous wave):
 * each placed point source's power P is shared among the 8 corners of the
 * grid cell containing it by trilinear weights, renormalised over the
 * corners that are interior nodes (none: all to the nearest interior node of
 * the 4^3, then 6^3 block; none there: an Error naming the source), and a
 * node's share p enters its row as h^2 p / V_u, V_u the node's control box
 * (ControlExtents). Every level gets them. Documentation/DiffuseOptics.md.
 *
 * Linear solvers (SetLinearSolver, case-insensitive): "bicgstab" (default;
 * BiCGSTAB with the diagonal preconditioner on the right, as Eigen's, with
 * deterministic parallel products and sums) or "relaxation" (Gauss-Seidel
 * in three colours: interior nodes of even i + j + k, of odd i + j + k, then
 * boundary nodes, each colour updated in parallel with the Jacobi-style
 * update of polygrid Sec. 5.2, phi_i <- (b_i - sum_j m_ij phi_j) / m_ii; one
 * iteration = one sweep of the three; the relative residual is checked after
 * every sweep). Relaxation needs O(n^2) sweeps for n nodes across: use it
 * with multi-level, or for comparison.
 *
 * Multi-level (SetMultiLevel, polygrid Sec. 5.3): coarser grids of spacing 2h,
 * 4h, ... whose nodes are the centres of 2x2x2 blocks of finer nodes, each
 * coarse interior node taking the mean mu_a and kappa of its interior
 * children (normalised by their number; the containing tet's values when it
 * has none) and each coarse boundary node the mean q of its children's
 * boundary nodes on the same side (else of all their boundary nodes, else
 * of the level). Solved coarsest first; each finer level starts from the
 * coarser solution interpolated at its nodes (as EvaluateGrid does). Levels
 * are added while the finer grid has more than 4096 unknowns and the coarser
 * keeps at least 512, at most 6 coarse levels.
 *
 * Warm start: when the grid is unchanged (same mesh object, same coordinates
 * and tets, i.e. the same TetMesh::GetGeometryRevision(), same spacing) the
 * previous fine solution is the initial guess; it takes precedence over the
 * multi-level initialisation.
 *
 * Fluence at the mesh points: EvaluateGrid at each point.
 *
 * Memory: before allocating, the grid's needs are estimated (4 bytes per grid
 * node of the box, ~400 per unknown, +1/7 with multi-level); above
 * SetMemoryLimit (default GetDefaultMemoryLimit(), 8 GiB; ResourceLimits.h) Solve throws an Error stating the bytes.
 *
 * Threads: results are bit-identical for any number of threads. By default
 * loops use at most one thread per 50,000 unknowns and let OpenMP reduce
 * the count on a busy machine (omp_set_dynamic during the solve).
 */
class GridSolver : public DiffusionSolver
{
public:
  std::string GetName() const override { return "grid"; }

  /// Solve with q interpolated on the hit triangles from problem.Irradiance.
  bool Solve(const DiffusionProblem& problem,
    std::vector<double>& fluence,
    SolverReport& report) override;

  /**
   * Solve with q given at the boundary nodes of the fine grid instead
   * (3 values per boundary node, W/mm^2, in the order of the boundary nodes;
   * e.g. an analytic source, or the virtual sources of inverse diffusion).
   * problem.Irradiance is not read (it may be null). Call PrepareGrid first
   * to learn the boundary nodes.
   */
  bool SolveWithNodeIrradiance(const DiffusionProblem& problem,
    const std::vector<double>& nodeIrradiance,
    std::vector<double>& fluence,
    SolverReport& report);

  /**
   * Build the grid for this mesh and the current spacing, or keep the one
   * built before if nothing changed (Solve calls it). Throws Error for an
   * empty mesh, an invalid spacing, a grid over the memory limit or a grid
   * with no node inside the mesh.
   */
  void PrepareGrid(const TetMesh& mesh);

  /// Forget the grid and the warm-start solution.
  void Reset() override;

  ///@{
  /// Voxel spacing h (mm, > 0). Default 0 = automatic (ComputeSpacing picks
  /// it from the mesh). Option DiffusionOption::GridSpacing ("grid-spacing").
  void SetGridSpacing(double h) { GridSpacing_ = h; }
  double GetGridSpacing() const { return GridSpacing_; }
  ///@}

  ///@{
  /// Coarse-to-fine initialisation (Polygrid Sec. 5.3, 8-children
  /// averaging; see the class comment). Default off. Option
  /// DiffusionOption::MultiLevel ("multilevel").
  void SetMultiLevel(bool on) { MultiLevel_ = on; }
  bool GetMultiLevel() const { return MultiLevel_; }
  ///@}

  /// Reads "grid-spacing" (>= 0) and "multilevel" (see DiffusionSolver::SetOptions).
  void SetOptions(const SolverOptions& options) override
  {
    options.ReadNumber(GetName(), DiffusionOption::GridSpacing, 0.0,
      "the voxel spacing must be > 0 mm (or 0 for automatic)", GridSpacing_);
    options.ReadFlag(GetName(), DiffusionOption::MultiLevel, MultiLevel_);
  }

  ///@{
  /// Memory the grid may use (bytes; default 4 GiB). Must be > 0.
  void SetMemoryLimit(std::size_t bytes) { MemoryLimit_ = bytes; }
  std::size_t GetMemoryLimit() const { return MemoryLimit_; }
  ///@}

  ///@{
  /// OpenMP threads of every loop of the solver (default 0: automatic, see
  /// the class comment). Results do not depend on it.
  void SetNumberOfThreads(int n) override { NumberOfThreads_ = n; }
  int GetNumberOfThreads() const { return NumberOfThreads_; }
  ///@}

  /// Spacing h (mm) that applies to the mesh: GetGridSpacing() if > 0, else
  /// the automatic (volume / number of tets)^(1/3): about one node per tet.
  /// Throws Error for an empty mesh or a negative or non-finite spacing.
  double ComputeSpacing(const TetMesh& mesh) const;

  /**
   * Estimated bytes the grid of spacing h needs for this mesh, and the
   * number of grid nodes of its box. Used for the memory guard.
   */
  double EstimateMemory(const TetMesh& mesh, double h, double* gridNodes = nullptr) const;

  // ---- the grid (valid after PrepareGrid or Solve) ----

  /// Spacing h actually used (mm).
  double GetSpacing() const;
  /// Nodes along x, y, z of the fine grid.
  std::array<int, 3> GetDimensions() const;
  /// Position of grid node (0, 0, 0) (mm).
  std::array<double, 3> GetOrigin() const;
  int GetNumberOfInteriorNodes() const;
  int GetNumberOfBoundaryNodes() const;
  /// Fine-level unknowns: interior nodes, then boundary nodes.
  int GetNumberOfUnknowns() const
  {
    return GetNumberOfInteriorNodes() + GetNumberOfBoundaryNodes();
  }
  /// Position (mm) of unknown u (interior node, or boundary node u - interior count).
  std::array<double, 3> GetNodePosition(int u) const;
  /// Grid index (i, j, k) of interior node u.
  std::array<int, 3> GetInteriorNodeIndex(int u) const;
  /// Interior node a boundary node is linked to.
  int GetBoundaryNodeInterior(int b) const;
  /// Direction of the link: 0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z.
  int GetBoundaryNodeDirection(int b) const;
  /// Link length d (mm; after clamping to [0.1 h, h]).
  double GetBoundaryNodeDistance(int b) const;
  /// Boundary triangle hit by the link (index into TetMesh::GetBoundaryTriangles).
  int GetBoundaryNodeTriangle(int b) const;
  /// Links whose surface point was not found by the ray along the link and
  /// came from the fallbacks (reverse ray, then the nearest triangle).
  int GetNumberOfRayFallbacks() const { return RayFallbacks_; }
  /// Levels of the grid: 1, or more once a solve with multi-level built them
  /// (kept, unused, if multi-level is switched off afterwards).
  int GetNumberOfLevels() const { return static_cast<int>(Levels_.size()); }
  /// Iterations spent on the coarse levels in the last solve, per channel.
  const std::array<int, NumberOfChannels>& GetCoarseIterations() const { return CoarseIterations_; }

  /// Level l of the grid (0 = fine; coarser ones with multi-level), for
  /// inspection. Valid until the grid is rebuilt.
  const GridLevel& GetLevel(int l) const;
  /// Fine-level system of the last solve (valid until the next).
  const DiffusionSystem& GetSystem() const;
  /// Fine-level solution of the last solve, per channel, one value per unknown.
  const std::array<Eigen::VectorXd, NumberOfChannels>& GetNodeFluence() const;

  /**
   * Fluence (3 values, W/mm^2) of the last fine solution at x (mm). If the 8
   * corners of the grid cell containing x are interior nodes: trilinear
   * interpolation. Otherwise a linear function a + g . (y - x) fitted by
   * weighted least squares (weights 1 / (|y - x|^2 / h^2 + 0.01)) to the
   * interior nodes among the 8 corners and the boundary nodes linked to
   * them; with fewer than 4 such nodes or a singular fit (smallest pivot
   * below 1e-8 of the largest), the same with the 4^3 block of nodes around
   * x, then the 6^3 block; if still none fits, their inverse-squared-distance
   * mean (and if these blocks have no interior node, the first larger block
   * that has one). A negative fitted value is set to 0. Both rules reproduce
   * linear fields exactly.
   */
  std::array<double, NumberOfChannels> EvaluateGrid(const double x[3]) const;

private:
  double GridSpacing_ = 0.0;
  bool MultiLevel_ = false;
  bool SolveImpl(const DiffusionProblem& problem,
    const std::vector<double>* nodeIrradiance,
    std::vector<double>& fluence,
    SolverReport& report);
  void CheckProblem(const DiffusionProblem& problem, bool needIrradiance) const;
  /// Builds the nodes of a level whose spacing, origin and dims are set;
  /// returns the number of ray fallbacks.
  int BuildLevel(const TetMesh& mesh, GridLevel& level) const;
  void Assemble(const TetMesh& mesh, const OpticalProperties& material, int levelIndex);
  /// Adds the interior sources to the right-hand side of a level's interior
  /// rows (after Assemble): trilinear weights, power / control volume.
  void AddInteriorSources(int levelIndex, const std::vector<PlacedSource>& sources);
  bool SolveLevel(GridLevel& level,
    bool guess,
    std::array<int, NumberOfChannels>& iterations,
    std::array<double, NumberOfChannels>& residual,
    std::array<bool, NumberOfChannels>& converged,
    double progressStart,
    double progressEnd);
  /// Threads for a loop over about work items: the setting, or by default
  /// one per 50,000 items (at least 1, at most OpenMP's).
  int Threads(long long work) const;

  std::vector<GridLevel> Levels_;
  /// The linear solver of the last Solve (registry, non-symmetric entries).
  std::unique_ptr<ChannelLinearSolver> Linear_;
  TetLocator Locator_;
  RayCaster Caster_;
  const TetMesh* Mesh_ = nullptr;
  std::uint64_t GeometryRevision_ = 0; ///< TetMesh::GetGeometryRevision() of the grid
  double RequestedSpacing_ = -1.0;
  bool HasMultiLevel_ = false;
  bool HaveSolution_ = false;
  int RayFallbacks_ = 0;
  std::array<int, NumberOfChannels> CoarseIterations_{};
  std::size_t MemoryLimit_ = GetDefaultMemoryLimit();
  int NumberOfThreads_ = 0;
};

} // namespace translucency
