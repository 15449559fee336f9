/**
 * @file SolutionRecycler.h
 * @brief Galerkin initial guesses from earlier solutions of the same SPD
 * matrices (three channels), for relighting while a light moves: the last k
 * solutions x_i and their products w_i = A x_i are kept, and a warm start
 * x0 becomes the A-norm-best combination of x0 and the x_i, per channel:
 * x = V c with (V^T A V) c = V^T b, V = [x0, x_1, ..., x_k] (the projection
 * of the solution onto span V; never worse than x0 in the A-norm).
 *
 * No extra product: A x0 comes from the solve's initial residual
 * r0 = b - A x0, and w_i from the final residual of the solve that found
 * x_i (w = b - r). The stored vectors are single precision by default, so
 * the new residual matches the new x to about 1e-7 |b|: use it with
 * tolerances well above that (multigrid-agg uses it with its
 * single-precision products, which have the same floor). With
 * SetDoublePrecision(true) they are kept in double precision (twice the
 * memory): the new residual then matches the new x to round-off, at any
 * tolerance (the time stepper's sequence of solves, TimeResolved.h). Cost:
 * two passes over x0, r0, b and the 2k stored vectors, and a copy of x and
 * b - r after the solve.
 */
#pragma once

#include "DiffusionSystem.h"

#include <array>
#include <cstddef>
#include <vector>

namespace translucency
{

class SolutionRecycler
{
public:
  /// Solutions kept, 0 (off, the default) to MaxCapacity.
  void SetCapacity(int k);
  int GetCapacity() const { return Capacity_; }
  static constexpr int MaxCapacity = 4;
  /// Solutions currently kept.
  int GetSize() const { return Size_; }
  /// Keep the solutions in double precision (default false: single). A
  /// change forgets the kept solutions.
  void SetDoublePrecision(bool on);
  bool GetDoublePrecision() const { return Double_; }
  /// Forget every solution (the matrix changed).
  void Clear() { Size_ = 0; }

  /**
   * Replace the warm start x (three channel arrays of n values) and its
   * residual r = b - A x (interleaved, 3n) by the projection onto span{x,
   * kept solutions}; returns r.r per channel after the update (deterministic
   * chunked sums). Without kept solutions of n unknowns only r.r is
   * computed.
   */
  std::array<double, NumberOfChannels> Project(int n, const std::array<const double*, NumberOfChannels>& b,
    const std::array<double*, NumberOfChannels>& x, double* r) const;
  /// Keep x and A x = b - r (r: the solve's final residual, interleaved),
  /// dropping the oldest solution beyond the capacity.
  void Store(int n, const std::array<const double*, NumberOfChannels>& b,
    const std::array<const double*, NumberOfChannels>& x, const double* r);

  std::size_t GetMemoryBytes() const;

private:
  template <typename T>
  std::array<double, NumberOfChannels> ProjectWith(const std::vector<std::vector<T>>& xs,
    const std::vector<std::vector<T>>& ws, int n,
    const std::array<const double*, NumberOfChannels>& b,
    const std::array<double*, NumberOfChannels>& x, double* r) const;
  template <typename T>
  void StoreIn(std::vector<std::vector<T>>& xs, std::vector<std::vector<T>>& ws, int n,
    const std::array<const double*, NumberOfChannels>& b,
    const std::array<const double*, NumberOfChannels>& x, const double* r);

  int Capacity_ = 0;
  int Size_ = 0;
  int N_ = -1;
  bool Double_ = false;
  /// Newest first: X_[i], W_[i] interleaved single precision (3n), or
  /// XD_[i], WD_[i] in double precision (SetDoublePrecision).
  std::vector<std::vector<float>> X_, W_;
  std::vector<std::vector<double>> XD_, WD_;
};

} // namespace translucency
