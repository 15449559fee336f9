/**
 * @file PowerReport.h
 * @brief Injected, absorbed and escaped power per channel of a diffusion
 * solve, for the JSON and the table of `render` and `compare`
 * (vtkSolveDiffusion::ComputePowerBalance; Documentation/DiffuseOptics.md).
 */
#pragma once

#include "vtk_nlohmannjson.h"
#include VTK_NLOHMANN_JSON(json.hpp)

#include <ostream>

class vtkSolveDiffusion;

namespace translucency_app
{

/**
 * {"R": {"injected", "absorbed", "escaped", "imbalance"}, "G": ..., "B": ...}
 * in W (imbalance = (absorbed + escaped - injected) / injected, 0 when
 * nothing is injected), or null when the solve has no steady-state balance
 * (frequency domain).
 */
nlohmann::json PowerBalanceJson(vtkSolveDiffusion* solve);

/// "power (W)   injected  absorbed  escaped  imbalance" lines, one per channel.
void PrintPowerBalance(const nlohmann::json& balance, std::ostream& out);

} // namespace translucency_app
