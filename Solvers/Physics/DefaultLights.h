/**
 * @file DefaultLights.h
 * @brief The one default lighting of every entry point: the CLI (no --light),
 * the VTK filter vtkSurfaceIrradiance (no light added) and the ParaView
 * Surface Irradiance panel's initial values.
 *
 * A key light travelling along (0, -1, -1) with irradiance 1 W/mm^2 on a
 * surface facing it, plus a uniform (environment) fill light of 0.1 W/mm^2,
 * white (the same in R, G, B). The fill light keeps the self-shadowed side
 * from being black; both are recorded in every output that reports lights.
 */
#pragma once

#include "LightSources.h"

#include <string>

namespace translucency
{

/// The default key light: directional, direction of travel (0, -1, -1),
/// irradiance 1 W/mm^2 per channel.
inline LightSource DefaultKeyLight()
{
  return DirectionalLight({ 0.0, -1.0, -1.0 }, { 1.0, 1.0, 1.0 });
}

/// The default uniform fill light's irradiance (W/mm^2 per channel).
constexpr double DefaultUniformIrradiance = 0.1;

/// The default lights in the CLI's --light syntax, as every report prints them.
inline std::string DescribeDefaultLights()
{
  return "directional:0,-1,-1:1 uniform:0.1";
}

} // namespace translucency
