/**
 * @file AimedPencilBeam.h
 * @brief A pencil beam given by two points (where it starts and where it
 * points), as ParaView's line widget places it: the entry point on the
 * surface is found by casting the ray.
 */
#pragma once

#include "InteriorSources.h"

#include <array>
#include <string>
#include <vector>

namespace translucency
{

class TetMesh;

/**
 * The pencil beam that starts at `start` (mm, outside the object) and
 * travels towards `towards` (mm): its entry point is the first point where
 * the ray from `start` along towards - start hits the mesh surface (a
 * RayCaster over the boundary triangles), its direction towards - start.
 * A `start` on the surface, or inside it by at most SurfaceTolerance(), is
 * taken as lying on it: the beam enters there.
 * `power` is in W per channel (R, G, B); `label` names the beam in errors.
 *
 * Throws translucency::Error naming the beam and the points when the two
 * points coincide (or a coordinate is not finite), when the ray misses the
 * object, and when `start` is inside the object (the first surface hit is
 * an exit: the beam must start outside). The returned beam is then placed
 * and validated by Sources::Place() like any other.
 */
PencilBeam AimPencilBeam(const TetMesh& mesh, const std::array<double, 3>& start,
  const std::array<double, 3>& towards, const std::array<double, NumberOfChannels>& power,
  const std::string& label);

/**
 * The same, on a boundary surface given by its triangles (`points`: 3
 * coordinates each, mm; `triangles`: 3 point ids each, outward), e.g. the
 * physical boundary all-gathered from a distributed mesh; `tolerance` takes
 * the place of SurfaceTolerance(mesh) (SurfaceTolerance of the triangles).
 */
PencilBeam AimPencilBeam(const std::vector<double>& points, const std::vector<int>& triangles,
  double tolerance, const std::array<double, 3>& start, const std::array<double, 3>& towards,
  const std::array<double, NumberOfChannels>& power, const std::string& label);

} // namespace translucency
