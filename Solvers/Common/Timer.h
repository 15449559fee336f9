/**
 * @file Timer.h
 * @brief The one wall-clock timer of the project: every "SetupMilliseconds",
 * "SolveMilliseconds" and timing-table figure is measured with it.
 */
#pragma once

#include <chrono>

namespace translucency
{

/// Monotonic clock of every timing (never the system clock).
using Clock = std::chrono::steady_clock;

/// Milliseconds elapsed since `start`.
inline double MillisecondsSince(Clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

/// Seconds elapsed since `start`.
inline double SecondsSince(Clock::time_point start)
{
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// A stopwatch started on construction.
class Timer
{
public:
  Timer()
    : Start_(Clock::now())
  {
  }
  /// Start again from now.
  void Restart() { Start_ = Clock::now(); }
  /// Milliseconds since construction or the last Restart().
  double GetMilliseconds() const { return MillisecondsSince(Start_); }
  /// Seconds since construction or the last Restart().
  double GetSeconds() const { return SecondsSince(Start_); }

private:
  Clock::time_point Start_;
};

} // namespace translucency
