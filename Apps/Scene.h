/**
 * @file Scene.h
 * @brief The scene shared by `render` and `compare`: what the scene options
 * describe (mesh, tetrahedralisation, material, edits, lights) and the
 * pipeline that turns it into a lit tet mesh.
 */
#pragma once

#include "Utilities.h"

#include <vtkSmartPointer.h>

#include <string>
#include <vector>

class vtkUnstructuredGrid;

namespace translucency_app
{

/// A light from --light: type directional|point|uniform, 3 values, power.
struct Light
{
  std::string Type;            ///< directional, point, spot, uniform or none
  double Values[3] = { 0, 0, 0 }; ///< direction (directional) or position (point, spot)
  double Power = 1.0;          ///< channel R's power (all channels unless Coloured)
  double PowerRGB[3] = { 1.0, 1.0, 1.0 }; ///< power per channel R, G, B
  bool Coloured = false;       ///< the power was given as R,G,B
  double Axis[3] = { 0, 0, -1 }; ///< spot: axis direction
  double Cutoff = 30.0;        ///< spot: cone half-angle (degrees)
  double Exponent = 0.0;       ///< spot: fall-off exponent
};
/// Parse a --light SPEC; a UsageError naming --light and the fault otherwise.
Light ParseLight(const std::string& spec);

/// What the scene options (Options.h, AddSceneOptions) set.
struct SceneOptions
{
  std::string MeshPath;
  std::string Material; ///< preset name or JSON file; empty: keep .vtu arrays or marble
  std::string MaterialIds; ///< cell array of material ids (with a JSON material table)
  long long TargetTets = 200000;
  bool TargetGiven = false;
  double MaxTetVolume = 0.0; ///< mm^3; 0: use TargetTets
  double Quality = 1.414;
  std::string Mesher = "tetgen"; ///< --mesher: tetgen or hxt
  bool UniformSizing = false;    ///< --uniform-size
  double GradingFactor = 0.0;    ///< --grading (0: off)
  std::vector<Light> Lights;
  bool DefaultLights = false; ///< no --light given: Finish() added the default lights
  bool Shadows = true;
  int UniformSamples = 32;
  /// --collimated: how directional lights enter the diffusion model:
  /// "default" (the core table's model per light kind,
  /// translucency::DefaultCollimatedModel) or a name of
  /// translucency::GetCollimatedModelTable().
  std::string Collimated = "default";
  std::vector<double> CutPlane; ///< --cut-plane: origin (mm) and normal; empty: no plane cut
  std::string CutStroke;        ///< --cut-stroke: JSON stroke file; empty: no stroke cut
  std::string Paint;            ///< --paint: JSON paint file; empty: no painting
  /// The command has interior sources (render --source): then no default
  /// lights are added when no --light is given.
  bool InteriorSources = false;

  /// Checks across options and the default lights, once all options are
  /// read (`command` names the command in messages). The default lights
  /// (directional:0,-1,-1:1 and uniform:0.1) are added when no --light is
  /// given and there are no interior sources; `--light none` (alone) means
  /// no light.
  void Finish(const std::string& command);

  /// The files the scene reads (--mesh, a --material .json, --paint,
  /// --cut-stroke) as inputs of `plan` (no output may be one of them).
  void AddInputs(OutputPlan& plan) const;
};

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

} // namespace translucency_app
