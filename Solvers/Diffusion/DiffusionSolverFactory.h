/**
 * @file DiffusionSolverFactory.h
 * @brief Every diffusion solver by name. The interface (DiffusionSolver.h)
 * sits below its implementations in Discretizations/ and Diffusion/; this
 * factory sits above them all.
 */
#pragma once

#include "DiffusionSolver.h"

#include <memory>
#include <string>
#include <vector>

namespace translucency
{

/// Names accepted by CreateDiffusionSolver, in the order they are listed.
std::vector<std::string> GetDiffusionSolverNames();

/**
 * A new solver by name (case-insensitive). Throws translucency::Error
 * naming the unknown name and listing the known ones.
 */
std::unique_ptr<DiffusionSolver> CreateDiffusionSolver(const std::string& name);

} // namespace translucency
