/**
 * @file JsonInputs.h
 * @brief The JSON files of the scene options: --material (a single material
 * or a material table), --paint (a paint stroke) and --cut-stroke (a cutting
 * stroke). Each loader configures its filter and throws translucency::Error
 * naming the file and the field on bad input.
 */
#pragma once

#include <string>

class vtkAssignScatteringCoefficients;
class vtkPaintScatteringCoefficients;
class vtkStrokeCut;

namespace translucency_app
{

/// Configure `assign` from --material (a preset name, a single-material JSON
/// file or a JSON material table) and --material-ids (the id array a table
/// needs).
void ApplyMaterial(vtkAssignScatteringCoefficients* assign, const std::string& material,
  const std::string& materialIds = std::string());

/// Configure `paint` from a --paint JSON file.
void ApplyPaintFile(vtkPaintScatteringCoefficients* paint, const std::string& path);

/// Configure `cut` from a --cut-stroke JSON file.
void ApplyStrokeFile(vtkStrokeCut* cut, const std::string& path);

} // namespace translucency_app
