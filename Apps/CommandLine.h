/**
 * @file CommandLine.h
 * @brief What the `translucency` commands share: option parsing for the
 * scene (mesh, material, lights), building the lit tet mesh, atomic writes,
 * and error collection from the filters.
 */
#pragma once

#include <vtkCallbackCommand.h>
#include <vtkNew.h>
#include <vtkSmartPointer.h>

#include <stdexcept>
#include "Timer.h"

#include <string>
#include <vector>

class vtkAssignScatteringCoefficients;
class vtkDataObject;
class vtkObject;
class vtkPolyData;
class vtkUnstructuredGrid;
class vtkXMLWriter;

namespace translucency_app
{
using translucency::Clock;
using translucency::MillisecondsSince;

/// A mistake in the command line (exit code 2).
struct UsageError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

/// One row of the timing table.
struct Stage
{
  std::string Name;
  double Milliseconds;
};

double Median(std::vector<double> values);
std::vector<double> ParseNumbers(const std::string& text, const std::string& what);
std::string Extension(const std::string& path);

/// Collects vtkErrorMacro text of the filters it watches; prints warnings.
struct MessageCollector
{
  std::string Errors;
  vtkNew<vtkCallbackCommand> ErrorCallback;
  vtkNew<vtkCallbackCommand> WarningCallback;
  vtkNew<vtkCallbackCommand> IgnoreCallback;
  MessageCollector();
  void Watch(vtkObject* algorithm);
  /// The message of the last error, without VTK's "ERROR: In file, line" header.
  std::string Last() const;
};

/// A light from --light: type directional|point|uniform, 3 values, power.
struct Light
{
  std::string Type;
  double Values[3] = { 0, 0, 0 };
  double Power = 1.0;
};
Light ParseLight(const std::string& spec);

/// Options that describe the scene, shared by `render` and `compare`.
struct SceneOptions
{
  std::string MeshPath;
  std::string Material; ///< preset name or JSON file; empty: keep .vtu arrays or marble
  std::string MaterialIds; ///< cell array of material ids (with a JSON material table)
  long long TargetTets = 200000;
  bool TargetGiven = false;
  double MaxTetVolume = 0.0;
  double Quality = 1.414;
  std::vector<Light> Lights;
  bool Shadows = true;
  int UniformSamples = 32;
  std::vector<double> CutPlane; ///< --cut-plane: origin (mm) and normal; empty: no plane cut
  std::string CutStroke;        ///< --cut-stroke: JSON stroke file; empty: no stroke cut
  std::string Paint;            ///< --paint: JSON paint file; empty: no painting

  /// If args[i] is a scene option, consume it (and its value) and return true.
  bool Parse(const std::vector<std::string>& args, size_t& i);
  /// Defaults and checks once all options are read (`command` names the command).
  void Finish(const std::string& command);
};

/// The options' help text, for --help.
extern const char* const SceneOptionsHelp;

/// Statistics of the optional --paint and --cut-* edits (for the JSON report).
struct EditStats
{
  bool Painted = false;
  long long PaintedTets = 0; ///< tets with PaintWeight > 1e-6
  double PaintMs = 0.0;
  bool Cut = false;
  long long KeptTets = 0;
  long long MovedVertices = 0;
  long long BlockedVertices = 0;
  double CutMs = 0.0;
};

/// Read, tetrahedralize, assign coefficients, paint (--paint), cut
/// (--cut-plane / --cut-stroke) and compute the irradiance, in that order.
/// Appends timing rows; `topologyMs` gets the topology time spent on the way;
/// `edits` (optional) gets the paint and cut statistics.
/// Throws translucency::Error with a message naming the problem (and the file).
vtkSmartPointer<vtkUnstructuredGrid> BuildLitMesh(const SceneOptions& options,
  std::vector<Stage>& stages, double& topologyMs, EditStats* edits = nullptr);

/// Read a surface (.ply .stl .obj .vtp) or a tet mesh (.vtu .node .ele).
bool ReadMesh(const std::string& path, vtkSmartPointer<vtkPolyData>& surface,
  vtkSmartPointer<vtkUnstructuredGrid>& grid, std::string& error);

/// Write `data` with `writer` to a temporary file, then rename it to `path`:
/// a failure leaves any existing `path` untouched.
bool WriteAtomically(vtkXMLWriter* writer, vtkDataObject* data, const std::string& path,
  std::string& error);
bool WriteText(const std::string& path, const std::string& text, std::string& error);
/// The points (x, y, z per point) and tets (4 point ids per cell) of a
/// tetrahedral grid as the Solvers/ core takes them.
void GridToCoreArrays(vtkUnstructuredGrid* grid, std::vector<double>& points, std::vector<int>& tets);
/// mkdir -p of the directory holding `path`.
void EnsureParentDirectory(const std::string& path);
/// Configure `assign` from --material (a preset name, a single-material JSON
/// file or a JSON material table) and --material-ids (the id array a table
/// needs). Throws translucency::Error naming the file on bad input.
void ApplyMaterial(vtkAssignScatteringCoefficients* assign, const std::string& material,
  const std::string& materialIds = std::string());
void PrintStages(const std::vector<Stage>& stages);

struct RadianceImageOptions;
/// If args[i] is a picture option (--exposure, --view, --up, --size), consume it
/// (and its value) into `image` and return true.
bool ParseImageOption(const std::vector<std::string>& args, size_t& i, RadianceImageOptions& image);

/// `translucency compare` (Compare.cxx) and its help text.
int Compare(const std::vector<std::string>& args);
/// `translucency radiosity` (Radiosity.cxx) and its help text.
int Radiosity(const std::vector<std::string>& args);
extern const char* const RadiosityHelp;
extern const char* const CompareHelp;

/// `translucency acquire` (Acquire.cxx): inverse diffusion, and its help text.
int Acquire(const std::vector<std::string>& args);
extern const char* const AcquireHelp;

} // namespace translucency_app
