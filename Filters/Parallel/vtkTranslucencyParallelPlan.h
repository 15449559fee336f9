/**
 * @file   vtkTranslucencyParallelPlan.h
 * @brief  What a filter does with more than one MPI process: the plan each
 *         filter declares once (its PlanParallel()), carried out by the one
 *         dispatcher (vtkTranslucencyDispatch.h). Private to the filters.
 *
 * Kinds (Documentation/Parallel.md, "What runs where"):
 *  - Serial: one process (or inside another filter's gathered run): the
 *    filter's serial code on the whole data. Never declared by a filter;
 *    it is what the dispatcher runs on a communicator of size one.
 *  - PerPiece: each rank runs on its own piece; the few whole-object
 *    quantities are reduced over the ranks (a sum, a front, a surface).
 *  - Distributed: each rank holds its piece of one distributed problem
 *    (hypre for Solve Diffusion, the all-gathered boundary for Irradiance).
 *  - Gathered: the pieces are merged on rank 0, the serial code runs there,
 *    the result goes back (GatherMode::SameMesh: each rank its own piece
 *    with the serial arrays; GatherMode::RankZero: the new data on rank 0).
 *
 * The one override: TRANSLUCENCY_PARALLEL=auto (default) or gathered (every
 * filter gathers); any other value is an error. The old per-filter variables
 * (TRANSLUCENCY_GATHERED_SOLVE, _IRRADIANCE, _RADIANCE, _CUT) are deprecated
 * aliases of "gathered" for their filter: set and not "" or "0".
 */
#ifndef vtkTranslucencyParallelPlan_h
#define vtkTranslucencyParallelPlan_h

#include "vtkTranslucencyParallel.h" // for vtkTranslucencyParallel::GatherMode

#include <string>

struct vtkTranslucencyParallelPlan
{
  enum class Kinds
  {
    Serial,
    PerPiece,
    Distributed,
    Gathered,
    /// Gathered to every rank: the serial path runs on each with the whole
    /// data and shares its work over the ranks (the Monte Carlo's photons,
    /// vtkTranslucencyParallel::RunGathered with `replicate`); the outputs
    /// go back as GatherMode::SameMesh.
    Replicated
  };
  using GatherMode = vtkTranslucencyParallel::GatherMode;

  Kinds Kind = Kinds::Serial;
  /// How the outputs go back when gathered (the declared kind or the override).
  GatherMode Mode = GatherMode::SameMesh;
  /// Why this plan, in a few words a user can act on.
  std::string Reason;
  /// The deprecated variable that forces this filter to gather (or null).
  const char* DeprecatedVariable = nullptr;

  static vtkTranslucencyParallelPlan PerPiece(GatherMode ifGathered, const std::string& reason);
  static vtkTranslucencyParallelPlan Distributed(GatherMode ifGathered, const std::string& reason);
  static vtkTranslucencyParallelPlan Gathered(GatherMode mode, const std::string& reason);
  static vtkTranslucencyParallelPlan Replicated(const std::string& reason);

  /// "serial", "per piece", "distributed", "gathered" or "replicated".
  const char* GetKindName() const;
  /// "per piece: <reason>", "gathered (same mesh): <reason>", ...
  std::string Describe() const;

  /// The override: false for auto (or unset), true for gathered. Throws
  /// translucency::Error for any other value of TRANSLUCENCY_PARALLEL.
  static bool ReadOverride();
  /// True if `variable` is set and not "" or "0".
  static bool IsSet(const char* variable);
};

#endif
