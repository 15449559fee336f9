/**
 * @file PipelineRender.h
 * @brief Pictures of a solved mesh for the command-line tool: the tone-mapped
 * radiance of the surface and a fluence slice with a colour bar.
 */
#pragma once

#include <string>

class vtkPolyData;
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

/// Render a slice of the fluence (red channel, log scale, colour bar) through
/// the centre of `mesh`, normal to the view direction.
bool WriteFluenceSlicePNG(vtkUnstructuredGrid* mesh, const RadianceImageOptions& options,
  const std::string& fileName, std::string& error);

} // namespace translucency_app
