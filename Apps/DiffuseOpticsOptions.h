/**
 * @file DiffuseOpticsOptions.h
 * @brief The diffuse-optics options of `render` (group "Diffuse optics"):
 * --source, --detector, --frequency, --time-gates (with --steps-per-gate
 * and --time-snapshots), their parsing, how they go to
 * vtkSolveDiffusion and the report (stdout and JSON).
 * Documentation/DiffuseOptics.md has the physics.
 */
#pragma once

#include <CLI/CLI.hpp>

#include "vtk_nlohmannjson.h"
#include VTK_NLOHMANN_JSON(json.hpp)

#include <array>
#include <string>
#include <vector>

class vtkSolveDiffusion;

namespace translucency_app
{

/// One --source: "point:x,y,z[:P]" or "pencil:x,y,z:dx,dy,dz[:P]"; P is one
/// power for the three channels or three (W; default 1).
struct SourceSpec
{
  std::string Spec; ///< as given, for messages and the report
  bool Pencil = false;
  std::array<double, 3> Position{};
  std::array<double, 3> Direction{};
  std::array<double, 3> Power{ 1.0, 1.0, 1.0 };
};
/// Parse a --source SPEC; a UsageError naming --source and the fault otherwise.
SourceSpec ParseSource(const std::string& spec);

/// One --detector: "x,y,z[:r]" (mm; r the fibre radius, default 0).
struct DetectorSpec
{
  std::string Spec;
  std::array<double, 3> Position{};
  double Radius = 0.0;
};
/// Parse a --detector SPEC; a UsageError naming --detector otherwise.
DetectorSpec ParseDetector(const std::string& spec);

/// --time-gates "T0,T1,N" (ns, ns, count): a UsageError naming
/// --time-gates and the fault (translucency::TimeGates::Check) otherwise.
struct TimeGatesSpec
{
  std::string Spec; ///< as given; empty = not time-resolved
  double Start = 0.0;
  double End = 0.0;
  int Count = 0;
};
TimeGatesSpec ParseTimeGates(const std::string& spec);

struct DiffuseOpticsOptions
{
  std::vector<SourceSpec> Sources;
  std::vector<DetectorSpec> Detectors;
  double Frequency = 0.0; ///< Hz; 0 = continuous wave (--frequency must be > 0)
  TimeGatesSpec TimeGates; ///< --time-gates
  int StepsPerGate = 0;    ///< --steps-per-gate; 0 = automatic
  std::vector<int> TimeSnapshots; ///< --time-snapshots (0-based gates)

  /// Give the sources, detectors, frequency and time gates to the filter
  /// (a UsageError for a snapshot gate >= N).
  void Apply(vtkSolveDiffusion* solve) const;
  /// Print the detector readings of the last solve (and, time-resolved, a
  /// table per detector: gate centre, fluence and exitance per channel).
  void Print(vtkSolveDiffusion* solve) const;
  /// The JSON entries "frequency_hz", "time_gates", "sources" and
  /// "detectors" (with the readings of the last solve; time-resolved, each
  /// detector's "tpsf").
  void Report(vtkSolveDiffusion* solve, nlohmann::json& j) const;
};

/// --source, --detector, --frequency, --time-gates, --steps-per-gate,
/// --time-snapshots on `command`.
void AddDiffuseOpticsOptions(CLI::App* command, DiffuseOpticsOptions& options);

} // namespace translucency_app
