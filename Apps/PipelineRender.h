/**
 * @file PipelineRender.h
 * @brief Pictures of a solved mesh for the command-line tool: the tone-mapped
 * radiance of the surface and a fluence slice with a colour bar.
 */
#pragma once

#include <string>
#include <vector>

class vtkPolyData;
class vtkRenderWindow;
class vtkUnstructuredGrid;

namespace translucency_app
{

/// Options of the radiance picture.
struct RadianceImageOptions
{
  int Width = 800;
  int Height = 600;
  /// Multiplies the radiance before the display transform; <= 0 selects it
  /// automatically (99th percentile of the brightest channel maps to 0.9).
  double Exposure = 0.0;
  /// Camera direction of view (from the camera towards the object).
  double ViewDirection[3] = { 0.0, 0.0, -1.0 };
  double ViewUp[3] = { 0.0, 1.0, 0.0 };
  /// Colour channel of the colour-mapped field pictures (0 R, 1 G, 2 B).
  int Channel = 0;
  /// Colour scale of the magnitude pictures (the fluence slice): log10 or linear.
  bool LogScale = true;
  /// Slice plane: origin (mm) and normal; empty: through the centre of the
  /// bounds, normal to the view direction.
  std::vector<double> SlicePlane;
};

/**
 * Add an unsigned char RGB point array "RadianceRGB" to `surface`: linear
 * radiance x exposure, then the sRGB transfer curve, clamped. Returns the
 * exposure used.
 */
double ToneMapRadiance(vtkPolyData* surface, double exposure);

/// Render the tone-mapped radiance of `surface` to a PNG (needs an X server).
/// Writes to a temporary file and renames. Returns false with `error` set.
bool WriteRadiancePNG(vtkPolyData* surface, const RadianceImageOptions& options,
  const std::string& fileName, std::string& error);

/// Render a slice of the fluence rate (options.Channel, log or linear
/// options.LogScale, inferno, colour bar in W/mm^2) on options.SlicePlane,
/// with the object's silhouette for context: `silhouette` (the mesh's
/// boundary surface, e.g. Outgoing Radiance's, when the caller has it), else
/// the boundary extracted from `mesh` (vtkDataSetSurfaceFilter).
bool WriteFluenceSlicePNG(vtkUnstructuredGrid* mesh, const RadianceImageOptions& options,
  const std::string& fileName, std::string& error, vtkPolyData* silhouette = nullptr);

/**
 * The frequency-domain slice (`render --frequency F --slice-png`): two panels
 * side by side on options.SlicePlane, each options.Width wide: the amplitude
 * `FluenceAmplitude` (inferno, log or linear as options.LogScale, W/mm^2 per
 * W of source) and the phase `FluencePhase` (viridis, linear, radians;
 * negative: the fluence lags the source), channel options.Channel;
 * `frequency` (Hz) goes into the captions.
 */
bool WriteAmplitudePhaseSlicePNG(vtkUnstructuredGrid* mesh, const RadianceImageOptions& options,
  double frequency, const std::string& fileName, std::string& error,
  vtkPolyData* silhouette = nullptr);

/**
 * Render `surface` coloured by its 1-component point array `arrayName` on the
 * linear range [lo, hi] (a shared scale across pictures): cool-warm if lo < 0
 * < hi (signed values), viridis otherwise, with a colour bar "quantity (unit)"
 * and `caption` above the object.
 */
bool WriteScalarMapPNG(vtkPolyData* surface, const char* arrayName, double lo, double hi,
  const std::string& quantity, const std::string& unit, const std::string& caption,
  const RadianceImageOptions& options, const std::string& fileName, std::string& error);

/// One curve of a line plot.
struct PlotSeries
{
  std::string Name;
  std::vector<double> X;
  std::vector<double> Y;
  /// Palette index: 0-5 the series colours (cycling), or PlotBlack, PlotGrey;
  /// -1 = the series' position.
  int Colour = -1;
  bool Dashed = false;  ///< a dashed line (with Markers: diamonds instead of circles)
  bool DashDot = false; ///< a dash-dot line (overrides Dashed for a line)
  bool Markers = false; ///< circles at the points, no line (e.g. Monte Carlo)
};
/// Palette indices beyond the 6 series colours (measured data, closed forms).
constexpr int PlotBlack = 6;
constexpr int PlotGrey = 7;

/**
 * A line plot (log-scale y) of several series, e.g. relative error against
 * wall time (TransCut Fig. 7 style).
 */
bool WritePlotPNG(const std::vector<PlotSeries>& series, const std::string& xTitle,
  const std::string& yTitle, const std::string& fileName, std::string& error,
  const std::string& title = std::string());

/// Render `window` and write it to a PNG through a temporary file renamed
/// into place. Returns false with `error` set.
bool Snapshot(vtkRenderWindow* window, const std::string& fileName, std::string& error);

} // namespace translucency_app
