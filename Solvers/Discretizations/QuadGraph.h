/**
 * @file QuadGraph.h
 * @brief Finite differences on the dual graph of the tetrahedral mesh: the
 * QuadGraph of Wang et al., "Real-time rendering of heterogeneous translucent
 * objects with arbitrary shapes" (QuadGraph, Sec. 4, eq. 5-10).
 *
 * Construction (paper Sec. 4.1): every tet with two or three boundary faces
 * is split at its centroid into four tets (one per face), so that every tet
 * of the split mesh has at most one boundary face. Each tet of the split mesh
 * ("cell") is an inner node at its centroid; two cells sharing a face are
 * linked; every boundary face carries one surface node linked to the cell
 * that owns the face. Inner nodes therefore have exactly four links, surface
 * nodes one. The surface node sits at the foot of the perpendicular from the
 * cell centroid to the face plane (the point where the link along the face
 * normal meets the face), so that the link difference of eq. 6 is a
 * derivative along the normal; d_sk is the centroid-to-plane distance.
 *
 * Equations, per channel (paper eq. 5 and 6, Stam's finite differences with
 * the inverse-square-distance Laplacian weights, alpha = -2):
 *  - inner node i:   sum_j kappa_j phi_j / d_ij^2 - (w kappa_i + mu_i) phi_i = 0,
 *                    w = sum_j 1 / d_ij^2 (the four links of i);
 *  - surface node s: phi_s + 2 A kappa_s (phi_s - phi_k) / d_sk = 4 q_s / (1 - Fdr),
 * with kappa, mu_a, eta of the node's (parent) tet and q_s interpolated
 * barycentrically on the boundary face from the per-point irradiance. The
 * matrix is not symmetric (kappa_j in row i): it is solved by BiCGSTAB with a
 * diagonal preconditioner (default) or by the paper's relaxation (eq. 8-9,
 * Jacobi sweeps).
 *
 * Multi-level initialisation (eq. 10, GetMultiLevel()): the paper
 * tetrahedralises simplified surfaces; this core has no mesher, so each
 * coarser level agglomerates the cells of the finer one in groups of eight
 * consecutive cells in Morton order (one coarse node at the group's
 * volume-weighted centroid, a coarse link wherever two groups share a link)
 * and the surface nodes of each group into one coarse surface node. The
 * coarsest level is solved from zero, each solution is interpolated to the
 * next finer level by inverse-square-distance (Shepard) weights over the 8
 * nearest coarse inner nodes / 4 nearest coarse surface nodes (searched in
 * the coarse parent's one-ring) and used there as the initial guess.
 *
 * Interior sources (DiffusionProblem::InteriorSources, continuous wave):
 * each placed point source's P1 load (P times its barycentric weights on
 * its tet's vertices) is carried to the nodes by the transpose of the vertex
 * map below: node k gets P sum_a lambda_a W(v_a, k), a cell as the density
 * share / V_k in its row, a surface node as the flux 2 A share / S_s on the
 * right-hand side of eq. 6 (like q). The two-point-flux scheme is then
 * reciprocal. Documentation/DiffuseOptics.md.
 *
 * Fluence at the mesh vertices (the output): for each vertex, a linear
 * least-squares fit, weighted by 1/distance^2, over the nodes of the cells
 * containing it and (boundary vertices) the surface nodes of the boundary
 * faces around it, evaluated at the vertex (exact for linear fields;
 * inverse-square-distance average where the fit is ill-conditioned), clamped
 * below at 0. See Documentation/Solvers.md.
 */
#pragma once

#include "DiffusionSolver.h"
#include "DiffusionSystem.h"
#include "LinearSolver.h"

#include <array>
#include <string>
#include <vector>

namespace translucency
{

class QuadGraphSolver : public DiffusionSolver
{
public:
  QuadGraphSolver();
  ~QuadGraphSolver() override;

  std::string GetName() const override { return "quadgraph"; }

  /**
   * Build the graph (when the mesh changed), assemble and solve the three
   * channels, map to the mesh points. Throws translucency::Error for a
   * missing or empty mesh, invalid material or irradiance, an interior
   * source outside the object (Sources::Place's messages), an unknown
   * GetLinearSolver() name, RelTol <= 0 or MaxIter <= 0. Returns false if the
   * progress callback aborted.
   */
  bool Solve(const DiffusionProblem& problem, std::vector<double>& fluence,
    SolverReport& report) override;

  /// Drop the graph and the warm-start solution.
  void Reset() override;

  ///@{
  /// Multi-level initialisation (QuadGraph eq. 10, see the class comment).
  /// Default off. Option DiffusionOption::MultiLevel ("multilevel").
  void SetMultiLevel(bool on) { MultiLevel_ = on; }
  bool GetMultiLevel() const { return MultiLevel_; }
  ///@}

  ///@{
  /**
   * NOT the paper's scheme, opt-in (default off): two-point finite-volume
   * link weights instead of eq. 5's inverse-square distances. Inner row i
   * becomes sum_j T_ij (phi_i - phi_j) + mu_i phi_i = 0 with
   * T_ij = kappa_ij S_ij / (V_i d_ij): S_ij the area of the face the link
   * crosses, V_i the cell volume, d_ij the link length, kappa_ij the
   * harmonic mean of the two cells' kappa (the cell's own kappa on a
   * surface link, whose length is the normal distance to the face). The
   * surface rows (eq. 6) are unchanged. It conserves light cell by cell on
   * graded meshes, where eq. 5 does not (Documentation/Solvers.md, "Use a
   * uniform mesh"). The multi-level guess keeps eq. 5 on the coarse levels.
   * Option DiffusionOption::TwoPointFlux ("two-point-flux").
   */
  void SetTwoPointFlux(bool on) { TwoPointFlux_ = on; }
  bool GetTwoPointFlux() const { return TwoPointFlux_; }
  ///@}

  /// Reads "multilevel" and "two-point-flux" (see DiffusionSolver::SetOptions).
  void SetOptions(const SolverOptions& options) override
  {
    options.ReadFlag(GetName(), DiffusionOption::MultiLevel, MultiLevel_);
    options.ReadFlag(GetName(), DiffusionOption::TwoPointFlux, TwoPointFlux_);
  }

  /// OpenMP threads for the graph build, assembly, the matrix products of
  /// both linear solvers and the vertex map (0 = OpenMP default). Default 0.
  /// Products and sweeps use one thread below 32,768 unknowns. Results do not
  /// depend on the number of threads (bit-identical).
  void SetNumberOfThreads(int n) override { NumberOfThreads_ = n; }
  int GetNumberOfThreads() const { return NumberOfThreads_; }

  /**
   * One level of the graph. Nodes are numbered cells first (inner nodes,
   * 0 .. NumberOfCells-1), then surface nodes. Positions in mm.
   */
  struct Level
  {
    int NumberOfCells = 0;
    int NumberOfSurfaceNodes = 0;
    int GetNumberOfNodes() const { return NumberOfCells + NumberOfSurfaceNodes; }
    std::vector<double> Positions;    ///< 3 per node (mm)
    std::vector<double> CellVolumes;  ///< per cell (mm^3)
    std::vector<double> SurfaceAreas; ///< per surface node (mm^2)
    std::vector<int> SurfaceCells;    ///< per surface node: the cell it is linked to
    /// Links of every node (CSR, sorted by node id): a cell's neighbour cells
    /// and surface node(s), a surface node's cell; with the link lengths (mm).
    std::vector<int> LinkOffsets;
    std::vector<int> LinkNodes;
    std::vector<double> LinkLengths;
    /// Finest level only: the area of the face each link crosses (mm^2;
    /// a surface node's link: its boundary triangle). Empty on coarse levels.
    std::vector<double> LinkAreas;
    /// Coarse levels only: for each node of the next finer level, the node
    /// of this level that contains it (a cell's group, a surface node's
    /// coarse surface node).
    std::vector<int> FineParents;
    /// Coarse levels only: eq. 10 weights, for each node of the next finer
    /// level, over nodes of this level (CSR).
    std::vector<int> ProlongationOffsets;
    std::vector<int> ProlongationNodes;
    std::vector<double> ProlongationWeights;
    /// The sparse pattern of this level's matrix (diagonal included).
    std::vector<int> RowOffsets;
    std::vector<int> ColumnIndices;
  };

  /// The finest level plus what ties it to the mesh.
  struct Graph
  {
    Level Fine;
    /// Per cell: the mesh tet it comes from, and -1 (tet not split) or the
    /// local face k (0..3, the face opposite tet vertex k) of the sub-tet.
    std::vector<int> CellTets;
    std::vector<int> CellFaces;
    /// Per surface node: its boundary triangle (index into
    /// TetMesh::GetBoundaryTriangles()) and the barycentric weights of the
    /// triangle's three points used to interpolate q there (the surface node
    /// itself, or its closest point on the triangle if it lies outside).
    std::vector<int> SurfaceTriangles;
    std::vector<double> SurfaceWeights;
    /// The split mesh: the mesh points followed by one centroid per split
    /// tet (3 per point, mm), and one tet (4 point ids) per cell.
    std::vector<double> SplitPoints;
    std::vector<int> SplitTets;
    int NumberOfSplitTets = 0;
    /// Vertex map: fluence at mesh point v = sum over k in
    /// [VertexOffsets[v], VertexOffsets[v+1]) of VertexWeights[k] * phi(VertexNodes[k]).
    std::vector<int> VertexOffsets;
    std::vector<int> VertexNodes;
    std::vector<double> VertexWeights;
    /// Coarser levels for the multi-level initialisation (built when first needed).
    std::vector<Level> Coarse;
  };

  /// The graph of the last Solve (empty before).
  const Graph& GetGraph() const { return Graph_; }
  /// Node values (cells then surface nodes) of the last Solve, per channel (W/mm^2).
  const std::array<Eigen::VectorXd, NumberOfChannels>& GetNodeFluence() const { return Solution_; }
  /// The fine system of the last Solve.
  const DiffusionSystem& GetSystem() const { return System_; }
  /// Time the last Solve spent building the graph (ms; 0 when it reused the
  /// graph of the previous Solve). Part of SolverReport::SetupMilliseconds.
  double GetGraphMilliseconds() const { return GraphMilliseconds_; }

private:
  bool MultiLevel_ = false;
  bool TwoPointFlux_ = false;
  /// Per-channel coefficients of the nodes (defined in the .cxx).
  struct Coefficients;

  void BuildGraph(const TetMesh& mesh, int numThreads);
  void BuildCoarseLevels(int numThreads);
  void ComputeFineCoefficients(const TetMesh& mesh, const OpticalProperties& material,
    const std::vector<double>& irradiance, Coefficients& coefficients, int numThreads) const;
  /// Adds the interior sources to the fine coefficients (after
  /// ComputeFineCoefficients): see the class comment.
  void AddSourceLoad(
    const TetMesh& mesh, const std::vector<PlacedSource>& placed, Coefficients& k) const;
  /// Solve one channel of one level's system from the guess in x; returns
  /// false if aborted.
  bool SolveChannel(const DiffusionSystem& system, int channel, Eigen::VectorXd& x,
    int& iterations, double& residual, bool& converged, double progressBase,
    double progressSpan, int numThreads) const;

  Graph Graph_;
  /// The linear solver of the last Solve (registry, non-symmetric entries).
  std::unique_ptr<ChannelLinearSolver> Linear_;
  DiffusionSystem System_;
  std::array<Eigen::VectorXd, NumberOfChannels> Solution_;
  /// What the graph was built from (to detect a changed mesh).
  const TetMesh* GraphMesh_ = nullptr;
  std::vector<double> GraphPoints_;
  std::vector<int> GraphTets_;
  bool HaveSolution_ = false;
  int NumberOfThreads_ = 0;
  double GraphMilliseconds_ = 0.0;
};

} // namespace translucency
