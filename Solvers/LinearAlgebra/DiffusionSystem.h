/**
 * @file DiffusionSystem.h
 * @brief A linear system per colour channel on one shared sparsity pattern.
 */
#pragma once

#include "OpticalProperties.h"

#include <Eigen/Sparse>

#include <array>
#include <vector>

namespace translucency
{

/// Row-major sparse matrix mapped on the shared pattern.
using SparseMatrixMap = Eigen::Map<const Eigen::SparseMatrix<double, Eigen::RowMajor, int>>;

/**
 * M_c x_c = b_c for c = R, G, B. The CSR pattern (RowOffsets, ColumnIndices)
 * is shared by the three channels; Values[c] holds the channel's entries.
 */
struct DiffusionSystem
{
  int NumberOfUnknowns = 0;
  std::vector<int> RowOffsets;    ///< size NumberOfUnknowns + 1
  std::vector<int> ColumnIndices; ///< sorted within each row
  std::array<std::vector<double>, NumberOfChannels> Values;
  std::array<Eigen::VectorXd, NumberOfChannels> RightHandSide;

  /// Bytes held: pattern, values and right-hand sides of the three channels.
  std::size_t GetMemoryBytes() const
  {
    std::size_t bytes = (RowOffsets.capacity() + ColumnIndices.capacity()) * sizeof(int);
    for (int c = 0; c < NumberOfChannels; ++c)
      bytes += Values[c].capacity() * sizeof(double) +
        static_cast<std::size_t>(RightHandSide[c].size()) * sizeof(double);
    return bytes;
  }

  /// The matrix of channel c as an Eigen map (no copy; valid while this lives).
  SparseMatrixMap Matrix(int c) const
  {
    return SparseMatrixMap(NumberOfUnknowns, NumberOfUnknowns,
      static_cast<int>(ColumnIndices.size()), RowOffsets.data(), ColumnIndices.data(),
      Values[c].data());
  }
};

} // namespace translucency
