/**
 * @file InteractiveAccuracy.h
 * @brief The default stopping rule of an interactive solve (issue 31;
 * Documentation/Solvers.md, "The interactive stopping rule").
 *
 * Stated as an accuracy: **the boundary fluence within 1 % (relative RMS
 * over the boundary points, each channel) of the converged solution**, for
 * a cold solve and for the warm-started solves of a relight or a paint
 * stroke, so that an interactive edit stops when the picture stops
 * changing. The vertex solvers' linear solvers stop on the relative
 * residual ||b - M x|| / ||b|| (checked on the true residual); the rule is
 * the residual InteractiveRelTol, chosen with a margin from measurements of
 * the boundary error against solves to 1e-10 (a marble sphere, a sphere
 * with a ketchup inclusion, the bunny at 10k to 1M tets; cg-jacobi and
 * multigrid-agg; cold, relight, paint): Solvers.md has the table,
 * Testing/Python/TestInteractiveAccuracy.py checks it and
 * `translucency bench --pipeline` reports it at 200k and 1M tets.
 *
 * Since session 26 a second test stops a channel first when the picture
 * stopped changing: the change rule (InteractiveChangeTol below), an
 * estimate of the boundary error left from the per-iteration changes.
 *
 * vtkSolveDiffusion's RelTol defaults to InteractiveRelTol; a user who
 * wants a tighter solve sets RelTol (e.g. 1e-10) and gets it. The core's
 * DiffusionSolver keeps its own default (1e-6) for the tests and benches
 * that set nothing.
 */
#pragma once

namespace translucency
{

/// The accuracy the interactive rule promises: boundary fluence within 1 %
/// (relative RMS, each channel) of the converged solution.
constexpr double InteractiveBoundaryAccuracy = 0.01;

/// The relative residual that meets InteractiveBoundaryAccuracy with a
/// margin of about 2 on every measured case (worst 0.53 %: a paint on the
/// 45k-tet bunny with cg-jacobi; Documentation/Solvers.md). A warm start
/// after a paint stroke iterates at least once (LinearSolver::SetMinIter).
constexpr double InteractiveRelTol = 1e-2;

/// The change rule of the interactive solve (DiffusionSolver::SetChangeTol,
/// LinearSolver::SetChangeRule): a channel also stops once the estimated
/// error of its boundary fluence (the geometric tail of the per-iteration
/// changes) is within this, relative RMS. Applied by vtkSolveDiffusion while
/// its RelTol is at least InteractiveRelTol.
constexpr double InteractiveChangeTol = 3e-3;

} // namespace translucency
