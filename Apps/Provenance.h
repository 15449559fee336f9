/**
 * @file Provenance.h
 * @brief Where a result came from, for every JSON the command-line tool
 * writes: the version, the source revision (git, captured when CMake
 * configured the build), the command line and every option's value
 * (defaults included), the lights, the material and the random seed.
 */
#pragma once

#include "vtk_nlohmannjson.h"
#include VTK_NLOHMANN_JSON(json.hpp)

#include <string>
#include <vector>

namespace CLI
{
class App;
}

namespace translucency_app
{
struct SceneOptions;

/// "0.1.0" (the CMake project version).
std::string ProjectVersion();
/// `git describe --always --dirty` of the source tree at configure time
/// ("unknown" outside a git checkout).
std::string SourceRevision();
/// "translucency 0.1.0 (revision ...)": what --version prints.
std::string VersionLine();

/// Remember the command line (main calls it once).
void SetCommandLine(int argc, char* argv[]);

/**
 * The "provenance" object: version, revision, command line, and the value
 * of every option of `command` as parsed (given or default).
 */
nlohmann::json Provenance(const CLI::App* command);

/// The scene part of the provenance: the lights (after the defaults were
/// added), the material specification and the mesh.
nlohmann::json SceneProvenance(const SceneOptions& scene);

/// "lights: directional:0,-1,-1:1 uniform:0.1 (the default)": the lights
/// in --light syntax, as the output reports them.
std::string LightsLine(const SceneOptions& scene);

} // namespace translucency_app
