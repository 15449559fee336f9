/**
 * @file LinearSolverCommon.h
 * @brief Helpers shared by the LinearSolver implementations (internal).
 */
#pragma once

#include "DiffusionSystem.h"
#include "Error.h"

#include <sstream>
#include <string>

namespace translucency
{

/// Throw translucency::Error (prefixed with `who`) unless the pattern arrays
/// describe an n x n CSR matrix and every channel has its values and
/// right-hand side.
inline void CheckLinearSystem(const DiffusionSystem& system, const std::string& who)
{
  const int n = system.NumberOfUnknowns;
  const size_t nnz = system.ColumnIndices.size();
  bool ok = n >= 0 && system.RowOffsets.size() == static_cast<size_t>(n) + 1 &&
    system.RowOffsets.front() == 0 && static_cast<size_t>(system.RowOffsets.back()) == nnz;
  for (int c = 0; ok && c < NumberOfChannels; ++c)
  {
    ok = system.Values[c].size() == nnz && system.RightHandSide[c].size() == n;
  }
  if (!ok)
  {
    std::ostringstream os;
    os << who << ": inconsistent system (" << n << " unknowns, " << system.RowOffsets.size()
       << " row offsets, " << nnz << " column indices, values " << system.Values[0].size() << "/"
       << system.Values[1].size() << "/" << system.Values[2].size() << ", right-hand sides "
       << system.RightHandSide[0].size() << "/" << system.RightHandSide[1].size() << "/"
       << system.RightHandSide[2].size() << ")";
    throw Error(os.str());
  }
}

} // namespace translucency
