/**
 * @file CompareTpsf.h
 * @brief `compare --time-gates ... --detector ...`: every solver's temporal
 * point-spread function (TPSF) at every detector on the same axes, and the
 * plot's data as a table (tpsf.csv, and "tpsf" in the JSON report).
 *
 * The readings are the gate averages of the fluence rate and of the
 * exitance (diffuse reflectance), both in J/(mm^2 ns) per J of pulse
 * (Documentation/DiffuseOptics.md, "Time domain"); Monte Carlo's come with
 * their standard errors (from its photon batches). The plot shows the
 * exitance: what a fibre collects, and what Monte Carlo tallies directly
 * (its boundary fluence is a track-length average over the tets around a
 * vertex, which reads high where the tets are larger than the transport
 * length; TestMonteCarloSources compares exitance for the same reason).
 */
#pragma once

#include "PipelineRender.h"

#include "vtk_nlohmannjson.h"
#include VTK_NLOHMANN_JSON(json.hpp)

#include <array>
#include <string>
#include <vector>

class vtkUnstructuredGrid;

namespace translucency_app
{

/// One solver at one detector: gate averages per gate and channel.
struct TpsfSeries
{
  std::string Solver;
  int Detector = 0; ///< 0-based
  std::vector<std::array<double, 3>> Fluence;  ///< [gate][channel], J/(mm^2 ns) per J
  std::vector<std::array<double, 3>> Exitance; ///< [gate][channel], J/(mm^2 ns) per J
  /// Standard errors, same shape; empty but for montecarlo.
  std::vector<std::array<double, 3>> FluenceError, ExitanceError;
};

/// A user's measured TPSF at one detector (`--measured FILE`, CompareMeasured.h).
struct MeasuredSeries
{
  int Detector = 0;    ///< 0-based
  std::string Column;  ///< its header in the file
  std::vector<double> Times; ///< ns (the file's rows; converted from ps if it says so)
  std::vector<double> Raw;   ///< the file's values (arbitrary units)
  double Scale = 1.0;        ///< the normalisation's factor (plotted = Scale x Raw)
  /// Scale x Raw interpolated linearly to the gate centres; NaN outside the measured times.
  std::vector<double> AtGates;
};

/// Every measured series and how they were normalised.
struct MeasuredOverlay
{
  std::string File;
  std::string TimeUnit;  ///< "ns" or "ps", as the header said
  std::string Normalise; ///< "area", "peak" or "none"
  std::string Reference; ///< the solver whose exitance it is scaled to
  int Channel = 0;       ///< the channel of that exitance (--channel)
  std::vector<MeasuredSeries> Series; ///< one per detector
};

/// The closed form at every detector (CompareClosedForm.h); empty Fluence when skipped.
struct ClosedFormOverlay
{
  std::string Name;       ///< e.g. "Patterson et al. 1989, semi-infinite, extrapolated boundary"
  std::string Assumption; ///< e.g. "semi-infinite, homogeneous"
  std::string SkipReason; ///< why it was not computed ("" = computed)
  /// [detector][gate][channel], J/(mm^2 ns) per J; a detector's entry is
  /// empty when the closed form does not apply there (DetectorSkipReasons).
  std::vector<std::vector<std::array<double, 3>>> Fluence, Exitance;
  std::vector<std::string> DetectorSkipReasons; ///< per detector, "" = computed
};

/// Every solver's series on the common gates.
struct TpsfTable
{
  std::vector<double> GateCentres;        ///< ns
  std::vector<std::string> DetectorSpecs; ///< as given to --detector
  std::vector<TpsfSeries> Series;         ///< solver-major, then detector
  MeasuredOverlay Measured;               ///< empty Series without --measured
  ClosedFormOverlay ClosedForm;           ///< empty Name when not asked for
};

/**
 * Read the TPSF field arrays (`TimeGateCentres`, `Detector{Fluence,Exitance}TPSF<k>`,
 * `Detector{Fluence,Exitance}TPSFStandardError<k>`) of each solver's output `volumes`
 * (same order as `solvers`). translucency::Error if a solver's output has
 * none or its gates differ from the first solver's.
 */
TpsfTable CollectTpsf(const std::vector<std::string>& solvers,
  const std::vector<vtkUnstructuredGrid*>& volumes, const std::vector<std::string>& detectorSpecs);

/// The table as CSV: a header line, then one row per gate: t_ns and, per
/// series, quantity (fluence, exitance) and channel,
/// `<solver>_d<k>_<quantity>_<C>` (k from 1; and `<...>_se` for Monte Carlo);
/// then `measured_d<k>` (the scaled measured curve at the gate centres, nan
/// outside its times) and `closedform_d<k>_<quantity>_<C>` when present.
std::string TpsfCsv(const TpsfTable& table);

/// The table as JSON: gate centres, units, and per series the readings and
/// standard errors per channel; "measured" and "closed_form" when present.
nlohmann::json TpsfJson(const TpsfTable& table);

/**
 * One plot of the exitance TPSF, channel `channel` (0..2): a colour per solver (Monte Carlo
 * as markers, the diffusion solvers as lines), solid lines and circles for
 * the 1st, 3rd, ... detector, dashed lines and diamonds for the 2nd, 4th,
 * ...; time in ns on x,
 * log-scale TPSF on y. Gates with no positive reading are left out of a
 * curve. The measured curves are black markers at their own times, the
 * closed form a grey dashed line (dash-dot for the even detectors), each
 * named in the legend with its normalisation or assumption. `caption` is
 * the plot's title.
 */
bool WriteTpsfPNG(const TpsfTable& table, int channel, const std::string& caption,
  const std::string& fileName, std::string& error);

} // namespace translucency_app
