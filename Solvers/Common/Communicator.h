/**
 * @file Communicator.h
 * @brief The communicator of a solve as the layers without MPI see it
 * (model: PETSc, where every object is created on an MPI_Comm and a serial
 * object is one on a communicator of size one).
 *
 * A Communicator is either *none* (the default: an in-process solve, no MPI
 * involved) or the address of an MPI_Comm that its creator owns (VTK's
 * vtkMPICommunicator, a bench's MPI_COMM_WORLD) with that communicator's
 * rank and size. Only the optional Parallel layer looks through the address
 * (Solvers/Parallel/MPICommunicator.h turns it back into an MPI_Comm and
 * makes one from an MPI_Comm); every other layer passes it on unopened, so
 * the core's MPI dependency stays in that layer. An MPI communicator of size
 * one (MPI_COMM_SELF) is still a distributed solve, on one rank: the same
 * code as on many, which is what lets the serial and distributed solvers be
 * compared in one process.
 */
#pragma once

#include <array>
#include <cstdint>

namespace translucency
{

class Communicator
{
public:
  /// None: the in-process (serial) solvers.
  Communicator() = default;
  /// `handle`: the address of an MPI_Comm that outlives every user of this
  /// object (not owned); `rank` and `size` are that communicator's.
  Communicator(const void* handle, int rank, int size)
    : Handle_(handle)
    , Rank_(rank)
    , Size_(size)
  {
  }

  /// True for an MPI communicator (of any size, one included).
  bool IsMPI() const { return Handle_ != nullptr; }
  /// The address of the MPI_Comm (null for none).
  const void* GetHandle() const { return Handle_; }
  int GetRank() const { return Rank_; }
  int GetSize() const { return Size_; }

private:
  const void* Handle_ = nullptr;
  int Rank_ = 0;
  int Size_ = 1;
};

/// A vertex's identity across the ranks of a distributed solve: a global
/// point id in [0] (zeros after it), or the bits of its three exact
/// coordinates (-0 taken as +0). Solvers/Parallel/DistributedNumbering.h.
using PointKey = std::array<std::uint64_t, 3>;

} // namespace translucency
