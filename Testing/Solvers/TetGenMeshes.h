/**
 * @file TetGenMeshes.h
 * @brief TetGen on a closed triangle surface for the tests that need
 * unstructured tets pointing every way (tests only: the core itself does not
 * use TetGen; the test program links Translucency::TetGen).
 */
#pragma once

#include "TestMeshes.h"

#ifndef TETLIBRARY
#define TETLIBRARY
#endif
#include <tetgen.h>

#include <algorithm>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

namespace translucency
{
namespace testing
{

/**
 * TetGen on a closed triangle surface; returns points and tets (0-based).
 * `extraPoints` (3 per point) are added inside as isolated vertices, and
 * `sizes` (one per surface point, then one per extra point; mm), when not
 * empty, is TetGen's point metric: the wanted edge length, interpolated
 * between the points (use it with the switch m).
 */
inline MeshData Tetrahedralize(const std::vector<double>& surfacePoints,
  const std::vector<int>& triangles, std::string switches,
  const std::vector<double>& extraPoints = {}, const std::vector<double>& sizes = {})
{
  tetgenio in, out;
  in.firstnumber = 0;
  const std::size_t numValues = surfacePoints.size() + extraPoints.size();
  in.numberofpoints = static_cast<int>(numValues / 3);
  in.pointlist = new REAL[numValues];
  std::copy(surfacePoints.begin(), surfacePoints.end(), in.pointlist);
  std::copy(extraPoints.begin(), extraPoints.end(), in.pointlist + surfacePoints.size());
  if (!sizes.empty())
  {
    if (sizes.size() != static_cast<std::size_t>(in.numberofpoints))
    {
      throw std::runtime_error("Tetrahedralize: one size per point expected");
    }
    in.numberofpointmtrs = 1;
    in.pointmtrlist = new REAL[sizes.size()];
    std::copy(sizes.begin(), sizes.end(), in.pointmtrlist);
  }
  in.numberoffacets = static_cast<int>(triangles.size() / 3);
  in.facetlist = new tetgenio::facet[in.numberoffacets];
  for (int f = 0; f < in.numberoffacets; ++f)
  {
    tetgenio::facet& facet = in.facetlist[f];
    tetgenio::init(&facet);
    facet.numberofpolygons = 1;
    facet.polygonlist = new tetgenio::polygon[1];
    tetgenio::init(&facet.polygonlist[0]);
    facet.polygonlist[0].numberofvertices = 3;
    facet.polygonlist[0].vertexlist = new int[3];
    for (int k = 0; k < 3; ++k)
    {
      facet.polygonlist[0].vertexlist[k] = triangles[3 * f + k];
    }
  }
  std::vector<char> sw(switches.begin(), switches.end());
  sw.push_back('\0');
  try
  {
    tetrahedralize(sw.data(), &in, &out);
  }
  catch (int code)
  {
    throw std::runtime_error("TetGen failed with code " + std::to_string(code));
  }
  MeshData mesh;
  mesh.Points.assign(out.pointlist, out.pointlist + 3 * static_cast<size_t>(out.numberofpoints));
  mesh.Tets.resize(4 * static_cast<size_t>(out.numberoftetrahedra));
  for (int t = 0; t < out.numberoftetrahedra; ++t)
  {
    for (int k = 0; k < 4; ++k)
    {
      mesh.Tets[4 * t + k] = out.tetrahedronlist[out.numberofcorners * t + k] - out.firstnumber;
    }
  }
  return mesh;
}

} // namespace testing
} // namespace translucency
