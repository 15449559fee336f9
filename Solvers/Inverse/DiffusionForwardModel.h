/**
 * @file DiffusionForwardModel.h
 * @brief The forward model of the inverse diffusion problem (Polygrid,
 * Sec. 4): for one colour channel and per-element diffusion coefficient kappa
 * and absorption mu_a, the SPD discrete-divergence system M(kappa, mu) phi = b
 * (TransCut Sec. 3, eq. 10-14; the same matrix as DiscreteDivergence), its
 * Cholesky factorisation (reused for all illumination patterns), the linear
 * radiance read-out and the derivative of M with respect to each element
 * parameter (for the adjoint gradient).
 */
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <memory>
#include <string>
#include <vector>

namespace translucency
{

class TetMesh;

/**
 * Parameters live on "elements": groups of tets sharing one kappa and one
 * mu_a (a voxel of a grid block split into tets, or a single tet). M is linear
 * in the parameters:
 *   M = sum_t [ 4 kappa_e(t) G_t + mu_e(t) V_t I_t ] + B,
 * with G_t the geometric stiffness of tet t (g_ab = N_a.N_b / (36 V_t)),
 * I_t the identity on its 4 vertices (lumped mass) and B the lumped Robin
 * term 2 S_i / (3 A) on the boundary diagonal; b_i = 8 S_i q_i /
 * (3 A (1 - Fdr)) (TransCut eq. 12-14). The refractive index is fixed
 * (not a parameter).
 */
class DiffusionForwardModel
{
public:
  /**
   * @param mesh tet mesh (kept by reference: must outlive this object)
   * @param tetElement element id of each tet, in [0, numElements)
   * @param numElements number of elements (every element must own a tet)
   * @param tetEta refractive index of each tet (> 0)
   * Throws translucency::Error on sizes or values that do not fit (named).
   */
  DiffusionForwardModel(const TetMesh& mesh, std::vector<int> tetElement, int numElements,
    const std::vector<double>& tetEta);

  /**
   * Element ids 0..E-1 from arbitrary integer labels per tet (a region or
   * voxel id array): the distinct labels in increasing order get 0, 1, ...
   * Returns the element of each tet; numElements receives E.
   */
  static std::vector<int> DenseElements(const std::vector<long long>& labels, int& numElements);
  ~DiffusionForwardModel();
  DiffusionForwardModel(const DiffusionForwardModel&) = delete;
  DiffusionForwardModel& operator=(const DiffusionForwardModel&) = delete;

  const TetMesh& GetMesh() const { return Mesh_; }
  int GetNumberOfElements() const { return NumberOfElements_; }
  int GetNumberOfPoints() const;
  const std::vector<int>& GetTetElements() const { return TetElement_; }
  /// Centroid of each element (3 per element, mm): volume-weighted tet centroids.
  const std::vector<double>& GetElementCentroids() const { return ElementCentroid_; }
  /// Volume of each element (mm^3).
  const std::vector<double>& GetElementVolumes() const { return ElementVolume_; }

  /**
   * Pairs of neighbouring elements (sharing tet faces across the element
   * boundary), each unordered pair once: 2 ids per pair. Used by the
   * gradient regulariser.
   */
  const std::vector<int>& GetElementNeighbours() const { return Neighbours_; }
  /// Per pair: A_ef / d_ef (mm), the shared face area over the distance of the
  /// element centroids (finite-volume weight of |grad kappa|^2).
  const std::vector<double>& GetElementNeighbourWeights() const { return NeighbourWeights_; }

  /// Read-out L_i = alpha_i phi_i - beta_i q_i at boundary point i (0 inside),
  /// from TransCut eq. 3 at normal exit: alpha = F_t(1)/(4 pi) (1 + 1/A),
  /// beta = F_t(1)/(4 pi) 4/(1 + Fdr). Not clamped at 0 (differentiable).
  const Eigen::VectorXd& GetReadOutFluenceWeights() const { return Alpha_; }
  const Eigen::VectorXd& GetReadOutIrradianceWeights() const { return Beta_; }

  /// b for the irradiance q (one value per mesh point, W/mm^2; only boundary
  /// points are read), TransCut eq. 12.
  Eigen::VectorXd Source(const Eigen::VectorXd& q) const;

  /**
   * A factorised system for one parameter set. Cheap to move; several can
   * coexist (the optimiser keeps the best and the trial point).
   */
  class Factor
  {
  public:
    Factor();
    ~Factor();
    Factor(Factor&&) noexcept;
    Factor& operator=(Factor&&) noexcept;
    /// x = M^-1 rhs.
    void Solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) const;
    /// X = M^-1 B for all columns at once (one blocked back-substitution:
    /// much faster than column by column with CHOLMOD).
    void Solve(const Eigen::MatrixXd& rhs, Eigen::MatrixXd& x) const;
    bool IsValid() const;

  private:
    friend class DiffusionForwardModel;
    struct Impl;
    std::unique_ptr<Impl> Impl_;
  };

  /**
   * Assemble M for per-element kappa (mm) and mu (1/mm), both > 0 and finite,
   * and factorise it (sparse Cholesky; the symbolic analysis, with its fill-
   * reducing ordering, is done on the first use of `factor` and kept: pass the
   * same Factor again for a new parameter set). Throws translucency::Error naming the element on a bad value.
   */
  void Factorize(const double* kappa, const double* mu, Factor& factor) const;

  /// The assembled matrix (lower and upper parts) for tests.
  Eigen::SparseMatrix<double> Matrix(const double* kappa, const double* mu) const;

  /**
   * The directional derivative of M: sum_e dKappa_e dM/dkappa_e + dMu_e
   * dM/dmu_e (M is linear in the parameters, so this is M(dKappa, dMu)
   * without the boundary term; directions may be negative or zero). Used for
   * tangent solves dphi = -M^-1 (dM) phi (Gauss-Newton steps of
   * InverseDiffusion). Throws on a non-finite direction, naming the element.
   */
  Eigen::SparseMatrix<double> DerivativeMatrix(const double* dKappa, const double* dMu) const;

  /**
   * Adds -lambda^T (dM/dkappa_e) phi to gKappa[e] and -lambda^T (dM/dmu_e)
   * phi to gMu[e] for every element (the adjoint gradient of a functional of
   * phi, where M lambda = dF/dphi).
   */
  void AccumulateGradient(const Eigen::Ref<const Eigen::VectorXd>& adjoint,
    const Eigen::Ref<const Eigen::VectorXd>& phi,
    double* gKappa, double* gMu) const;

  /// Name of the direct solver in use ("eigen-simplicial-ldlt" or
  /// "cholmod-supernodal").
  static std::string GetFactorizationName();

  /**
   * Threads of the BLAS under CHOLMOD's supernodal factorisation, if that BLAS
   * is OpenBLAS (found at run time; otherwise nothing happens). Returns the
   * previous count (0 if unknown). InverseDiffusion::Run sets 1 while it runs
   * the channels in parallel: OpenBLAS threads inside OpenMP threads
   * oversubscribe the cores (measured 4x slower on 2 cores).
   */
  static int SetBlasThreads(int n);

private:
  /// M(kappa, mu) on the mesh pattern, with or without the boundary term
  /// and the identity rows of unused points.
  Eigen::SparseMatrix<double> Assemble(const double* kappa, const double* mu, bool boundary) const;

  const TetMesh& Mesh_;
  std::vector<int> TetElement_;
  int NumberOfElements_ = 0;
  std::vector<double> TetStiffness_; ///< 10 per tet: g00 g11 g22 g33 g01 g02 g03 g12 g13 g23
  std::vector<double> ElementCentroid_;
  std::vector<double> ElementVolume_;
  std::vector<int> Neighbours_;
  std::vector<double> NeighbourWeights_;
  Eigen::VectorXd BoundaryDiagonal_; ///< 2 S_i / (3 A)
  Eigen::VectorXd SourceScale_;      ///< 8 S_i / (3 A (1 - Fdr))
  Eigen::VectorXd Alpha_, Beta_;
};

} // namespace translucency
