/**
 * @file CollimatedModels.h
 * @brief The one table of the collimated-source models and of the default
 * model per light kind (issue 33), read by vtkSurfaceIrradiance (its
 * CollimatedModel default), the ParaView plugin's Collimated Model list
 * (tested against this table) and the CLI's `--collimated` option and help.
 *
 * The defaults come from a measured table against the project's Monte Carlo
 * (Documentation/DiffuseOptics.md, "Which collimated model by default";
 * reproduced by scripts/collimated_model_table.py): per light kind, the
 * model whose fluence by depth, transmittance, exitance and radiance are
 * nearest the transport solution.
 */
#pragma once

#include "CollimatedSource.h"
#include "LightSources.h"

#include <string>
#include <vector>

namespace translucency
{

/// One collimated-source model: its name (what users type), the plugin's
/// label and one line of help. In the order of CollimatedModel's values
/// (the filter's and the plugin's integers).
struct CollimatedModelEntry
{
  CollimatedModel Model;
  std::string Name;
  std::string Label;
  std::string Help;
};

/// The models, in CollimatedModel's order (surface, extended, extended-moments).
const std::vector<CollimatedModelEntry>& GetCollimatedModelTable();

/// The entry called `name` (case-insensitive); throws translucency::Error
/// naming the unknown name and the known ones ("default" is not a model:
/// see DefaultCollimatedModel()).
const CollimatedModelEntry& GetCollimatedModel(const std::string& name);

/// The entry of `model`.
const CollimatedModelEntry& GetCollimatedModel(CollimatedModel model);

/// The kinds of light a scene can have, as the default table lists them.
enum class LightKind
{
  Directional, ///< a white directional (collimated, broad) light
  Coloured,    ///< a directional light with different R, G, B
  Spot,        ///< a spot light (a point light with a cone: boundary irradiance)
  Point,       ///< a point light (boundary irradiance)
  Uniform,     ///< the uniform (environment) light (boundary irradiance)
  Pencil,      ///< a pencil beam (vtkSolveDiffusion's, an interior source)
  None         ///< no light nor pencil beam (interior point sources only)
};

/// One row of the default table: a light kind, its default model and why
/// (the measured numbers, one line).
struct CollimatedDefault
{
  LightKind Kind;
  std::string KindName;
  CollimatedModel Model;
  std::string Why;
};

/// The defaults per light kind, in the order in which a scene with several
/// kinds decides: the first kind present chooses (one solve has one Robin
/// rule; the directional lights are what the extended models change).
const std::vector<CollimatedDefault>& GetCollimatedDefaultTable();

/// The default model of one light kind.
CollimatedModel DefaultCollimatedModel(LightKind kind);

/// The kind of a light (Directional, Coloured, Spot or Point).
LightKind KindOfLight(const LightSource& light);

/**
 * The default model of a scene: the default of the first kind of the
 * default table that the scene has (`lights`, the uniform light if
 * `uniformLight`, pencil beams if `pencilBeams`); None's default when it has
 * none of them.
 */
CollimatedModel DefaultCollimatedModel(
  const std::vector<LightSource>& lights, bool uniformLight, bool pencilBeams);

/// "  name   help" lines of every model, and a last line on the default per
/// light kind (the CLI's --collimated help).
std::string FormatCollimatedModelHelp(const std::string& indent = "  ");

/// One line: "directional: extended-moments, coloured: ..., pencil: surface".
std::string DescribeCollimatedDefaults();

} // namespace translucency
