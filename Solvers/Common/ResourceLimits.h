/**
 * @file ResourceLimits.h
 * @brief Guards against problem sizes and numbers the machine cannot hold:
 * a memory estimate checked against a limit before anything is allocated,
 * doubles range-checked before they become integers, and fields checked for
 * finiteness before they are reported as a result.
 *
 * The memory limit is one setting: every core object that can be asked for
 * an arbitrarily large problem (grid solver, tetrahedralisation, radiosity
 * patches and form factors, Monte Carlo photons, acquisition grids) starts
 * with GetDefaultMemoryLimit() (8 GiB unless SetDefaultMemoryLimit changed
 * it) and has its own SetMemoryLimit. The CLI's `--memory-limit GiB` sets the
 * default for the whole run. The model is the grid solver's guard
 * (Discretizations/GridSolver.cxx, PrepareGrid).
 */
#pragma once

#include "Error.h"

#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string>
#include <type_traits>

namespace translucency
{

/// How every memory-limit message names the override.
inline const char* MemoryLimitOverride()
{
  return "raise the limit with --memory-limit GiB, or SetMemoryLimit / "
         "translucency::SetDefaultMemoryLimit";
}

namespace detail
{
inline std::atomic<std::size_t>& DefaultMemoryLimitStorage()
{
  static std::atomic<std::size_t> limit{ std::size_t(8) << 30 };
  return limit;
}
} // namespace detail

namespace detail
{
inline std::atomic<bool>& LongRunsAllowedStorage()
{
  static std::atomic<bool> allowed{ false };
  return allowed;
}
} // namespace detail

/**
 * Work budgets (Monte Carlo photons, form-factor rays, the acquisition's
 * estimated solve work) refuse a request that would run for hours unless
 * long runs are allowed: the CLI's `--allow-long-runs`, or this setting
 * (default false). Memory limits are separate (SetDefaultMemoryLimit).
 */
inline void SetLongRunsAllowed(bool allowed)
{
  detail::LongRunsAllowedStorage().store(allowed);
}

/// Whether work budgets are lifted (SetLongRunsAllowed; default false).
inline bool GetLongRunsAllowed()
{
  return detail::LongRunsAllowedStorage().load();
}

/// How every work-budget message names the override.
inline const char* LongRunOverride()
{
  return "pass --allow-long-runs, or translucency::SetLongRunsAllowed(true)";
}

/// The memory limit new core objects start with, bytes (default 8 GiB).
inline std::size_t GetDefaultMemoryLimit()
{
  return detail::DefaultMemoryLimitStorage().load();
}

/// Set the memory limit new core objects start with, bytes (> 0).
inline void SetDefaultMemoryLimit(std::size_t bytes)
{
  if (bytes == 0)
  {
    throw Error("the memory limit is 0 bytes: it must be > 0");
  }
  detail::DefaultMemoryLimitStorage().store(bytes);
}

/// A number for a message: %g-style, 4 significant digits (1e+100, not 200 digits).
inline std::string FormatNumber(double value)
{
  std::ostringstream os;
  os << std::setprecision(4) << value;
  return os.str();
}

/// "12.3 GiB (1.321e+10 bytes)" or "512 MiB (...)".
inline std::string FormatBytes(double bytes)
{
  std::ostringstream os;
  os << std::setprecision(3);
  if (bytes >= 1024.0 * 1024.0 * 1024.0)
  {
    os << bytes / (1024.0 * 1024.0 * 1024.0) << " GiB";
  }
  else
  {
    os << bytes / (1024.0 * 1024.0) << " MiB";
  }
  os << " (" << std::setprecision(4) << bytes << " bytes)";
  return os.str();
}

/**
 * Throw Error unless `bytes` (an estimate, may be inf or NaN when the sizes
 * overflow) fits in `limit`: "<what> needs about X; the limit is Y: <advice>
 * (or raise the limit with ...)".
 */
inline void CheckMemory(
  const std::string& what, double bytes, std::size_t limit, const std::string& advice)
{
  if (limit == 0)
  {
    throw Error(what + ": the memory limit is 0 bytes: it must be > 0");
  }
  if (bytes <= static_cast<double>(limit))
  {
    return; // also false for NaN: refused below
  }
  throw Error(what + " needs about " +
    (std::isfinite(bytes) ? FormatBytes(bytes) : std::string("more memory than can be counted")) +
    "; the limit is " + FormatBytes(static_cast<double>(limit)) + ": " + advice + " (or " +
    MemoryLimitOverride() + ")");
}

/**
 * `value` as the integer type T, or Error "<name>: <value> is not a whole
 * number from <min> to <max>" (NaN, inf, fractions and out-of-range values
 * would be undefined behaviour in a cast). `min` and `max` narrow the range.
 */
template <class T>
T CheckedInteger(double value, const std::string& name,
  T min = std::numeric_limits<T>::lowest(), T max = std::numeric_limits<T>::max())
{
  static_assert(std::is_integral<T>::value, "CheckedInteger converts to integers");
  // max as a double can round up (2^63 - 1 -> 2^63): above 2^53 compare with
  // max + 1 = 2 * (max / 2 + 1), which is exact.
  const bool exact = static_cast<double>(max) <= 9007199254740992.0;
  const bool belowMax = exact ? value <= static_cast<double>(max)
                              : value < 2.0 * (static_cast<double>(max / 2) + 1.0);
  if (!(value >= static_cast<double>(min)) || !belowMax || value != std::floor(value))
  {
    std::ostringstream os;
    os << name << ": " << std::setprecision(17) << value << " is not a whole number from "
       << +min << " to " << +max;
    throw Error(os.str());
  }
  return static_cast<T>(value);
}

/**
 * Throw Error if a value of `data[0, count)` is NaN or infinite:
 * "<quantity> is not finite (<value> at index i of n)<cause>". `cause` is
 * appended as is (e.g. "; the light power is probably too large (overflow)").
 */
template <class Range>
void RequireFinite(const Range& data, const std::string& quantity, const std::string& cause)
{
  std::size_t index = 0;
  for (const auto& value : data)
  {
    if (!std::isfinite(static_cast<double>(value)))
    {
      std::ostringstream os;
      os << quantity << " is not finite (" << static_cast<double>(value) << " at index " << index
         << " of " << data.size() << ")" << cause;
      throw Error(os.str());
    }
    ++index;
  }
}

/// Likely cause of a non-finite field computed from the lights.
inline const char* OverflowCause()
{
  return ": the computation overflowed; the light power (or the model scale) is probably too "
         "large for double precision";
}

} // namespace translucency
