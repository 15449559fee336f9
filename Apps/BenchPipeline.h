/**
 * @file BenchPipeline.h
 * @brief `translucency bench --pipeline`: the ParaView chain a user drives,
 * timed filter by filter (BenchPipeline.cxx).
 *
 * The bunny is tetrahedralised once per size and written to a temporary
 * .vtu; the chain reads it like a user's pvbatch script (VTK XML reader),
 * then Assign (marble) -> Surface Irradiance (directional (0, -1, -1) 1
 * W/mm^2 + the default uniform light 0.1 W/mm^2) -> Paint Scattering
 * Coefficients (a stroke outside the object) -> Solve Diffusion (defaults)
 * -> Outgoing Radiance, each filter's Update() timed, for four steps:
 *  - cold: a new chain (every filter executes);
 *  - relight: the directional light turned 15 degrees about the x axis;
 *  - paint: the stroke moved onto the object (about 1 % of the tets);
 *  - cut: a plane through the centre (vtkStrokeCut) put between Paint and
 *    Solve Diffusion.
 * Medians of --runs, in ms and in SpMV units (one 1-channel product of the
 * discrete divergence matrix, timed in the same run). The relit and
 * painted fluence are compared with a solve to RelTol 1e-10 of the same
 * input (boundary RMS error), and the relit irradiance with a new Surface
 * Irradiance of the relit lights (no cache). `--collimated` sets Surface
 * Irradiance's collimated model (default: by light kind, extended-moments:
 * the relight then recomputes the beam's volume source), so the default
 * and the surface model's relight compare on the same tets.
 */
#pragma once

#include <string>
#include <vector>

namespace translucency_app
{

/// The options of `translucency bench --pipeline` (declared in BenchCommand.cxx).
struct PipelineBenchOptions
{
  std::string MeshPath = "Data/bunny.ply";
  std::vector<double> Tets = { 200000, 1000000 };
  int Runs = 3;
  std::string JsonPath;
  /// Surface Irradiance's collimated model by name (--collimated; "default":
  /// by light kind, extended-moments for the chain's directional light).
  std::string Collimated = "default";
};

/// `translucency bench --pipeline ...`.
int BenchPipeline(const PipelineBenchOptions& options);

} // namespace translucency_app
