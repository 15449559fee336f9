/**
 * @file DiffusionFrontEnd.h
 * @brief One diffusion solver kept across the solves of a changing scene
 * (relight, paint, cut), with the bookkeeping an interactive front end
 * needs: the solver by name (GetDiffusionSolverRegistry()), a new solver
 * or a new mesh forgets the warm start, and after a paint only the changed
 * tets are re-assembled (TransCut Sec. 5.2). vtkSolveDiffusion converts its
 * input and calls this.
 *
 * Incremental assembly (vertex solvers, IncrementalAssembly on): the front
 * end keeps the material and the irradiance of its last successful solve
 * (7 doubles per tet and 3 per point, moved in, not copied). When the next
 * solve has the same mesh object (same topology and points: a TetMesh
 * shared by the pipeline is keyed by both), the same irradiance (bit for
 * bit) and at most MaximumChangedFraction of the tets have another mu_a,
 * sigma_s' or eta (compared bit for bit, so any change is seen, whoever
 * made it), it hands those tets to VertexDiffusionSolver::SetChangedTets:
 * only their vertices' rows are rebuilt (the system equals a full
 * assembly) and the solve warm-starts from the previous fluence. Beyond the
 * fraction a parallel full assembly is faster than the serial row update.
 *
 * Why here and not in VertexDiffusionSolver: the cache is a policy of
 * interactive use (memory for a copy of the material, a comparison per
 * solve) that the other users of the solver (inverse diffusion, tests,
 * benchmarks) do not want; VertexDiffusionSolver keeps its explicit
 * SetChangedTets contract, and this class also owns the choice of solver
 * by name, which only this layer (above every solver) can make.
 */
#pragma once

#include "DiffusionSolver.h"

#include <memory>
#include <string>
#include <vector>

namespace translucency
{

class DiffusionFrontEnd
{
public:
  DiffusionFrontEnd();
  ~DiffusionFrontEnd();

  /**
   * The solver by name (case-insensitive, GetDiffusionSolverNames();
   * default "divergence"). Another name creates a new solver (its settings
   * are the defaults again) and forgets the warm start; the same name keeps
   * the solver. Throws translucency::Error for an unknown name (the solver
   * is then unchanged).
   */
  void SetSolver(const std::string& name);
  /// The registry name of the current solver.
  const std::string& GetSolverName() const { return SolverName_; }
  /// The current solver, to set its parameters (RelTol, options, ...).
  DiffusionSolver& GetSolver() { return *Solver_; }

  ///@{
  /// Re-assemble only the changed tets after a paint (see the file
  /// comment). Default on. Off also drops the cached material.
  void SetIncrementalAssembly(bool on);
  bool GetIncrementalAssembly() const { return IncrementalAssembly_; }
  ///@}

  ///@{
  /// Largest fraction of changed tets (in [0, 1]) for which the update is
  /// incremental. Default 0.05.
  void SetMaximumChangedFraction(double fraction) { MaximumChangedFraction_ = fraction; }
  double GetMaximumChangedFraction() const { return MaximumChangedFraction_; }
  ///@}

  /**
   * Solve on `mesh` with this material and irradiance (q, 3 per point,
   * W/mm^2); `light` gives the lights, UniformIrradiance and Shadows (its
   * Mesh, Material and Irradiance are ignored). Material and irradiance are
   * taken by value: move them in, the front end keeps them for the next
   * comparison. Another mesh object than the last one resets the solver
   * (no warm start). Returns false if the solver's progress callback
   * aborted (the cache is then forgotten); throws translucency::Error as
   * the solver does (the cache is then forgotten and the solver reset).
   */
  bool Solve(std::shared_ptr<const TetMesh> mesh, OpticalProperties material,
    std::vector<double> irradiance, const DiffusionProblem& light, std::vector<double>& fluence,
    SolverReport& report);

  /// Tets found changed for the last solve's incremental update; -1 if it
  /// did not look (not a vertex solver, IncrementalAssembly off, no cached
  /// solve, another mesh, another irradiance, or more changed tets than
  /// MaximumChangedFraction allows).
  long long GetNumberOfChangedTets() const { return ChangedTets_; }

  /// Forget the mesh, the cache and the warm start (keeps the solver and
  /// its settings).
  void Reset();

  /**
   * Ids of the tets whose mu_a, sigma_s' or eta differ between `a` and `b`
   * (same sizes), compared as bits (a NaN that stays a NaN is no change),
   * stopping once more than `limit` are found.
   */
  static std::vector<int> FindChangedTets(
    const OpticalProperties& a, const OpticalProperties& b, std::size_t limit);

private:
  void ForgetLast();

  std::string SolverName_;
  std::unique_ptr<DiffusionSolver> Solver_;
  std::shared_ptr<const TetMesh> Mesh_;
  bool IncrementalAssembly_ = true;
  double MaximumChangedFraction_ = 0.05;
  /// Material and irradiance of the last successful vertex solve; HaveLast_
  /// is false when they are not valid.
  bool HaveLast_ = false;
  OpticalProperties LastMaterial_;
  std::vector<double> LastIrradiance_;
  long long ChangedTets_ = -1;
};

} // namespace translucency
