/**
 * @file TetGenMeshes.h
 * @brief TetGen on a closed triangle surface for the tests that need
 * unstructured tets pointing every way (tests only: the core itself does not
 * use TetGen; the test program links Translucency::TetGen), and the surfaces
 * they mesh: Data/bunny.ply (ReadPly) and an icosphere.
 */
#pragma once

#include "TestMeshes.h"

#ifndef TETLIBRARY
#define TETLIBRARY
#endif
#include <tetgen.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
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

/// Reads the ASCII PLY of Data/bunny.ply: header, "x y z" lines, "3 a b c" lines.
inline void ReadPly(const std::string& path, std::vector<double>& points, std::vector<int>& triangles)
{
  std::ifstream in(path);
  if (!in)
  {
    throw std::runtime_error("cannot open " + path);
  }
  std::string line;
  int numVertices = -1, numFaces = -1;
  while (std::getline(in, line) && line != "end_header")
  {
    std::istringstream words(line);
    std::string keyword, element;
    int count = 0;
    if (words >> keyword >> element >> count && keyword == "element")
    {
      if (element == "vertex")
      {
        numVertices = count;
      }
      else if (element == "face")
      {
        numFaces = count;
      }
    }
  }
  if (numVertices <= 0 || numFaces <= 0)
  {
    throw std::runtime_error("bad PLY header in " + path);
  }
  points.resize(3 * static_cast<size_t>(numVertices));
  for (double& x : points)
  {
    in >> x;
  }
  triangles.resize(3 * static_cast<size_t>(numFaces));
  for (int f = 0; f < numFaces; ++f)
  {
    int n = 0;
    in >> n >> triangles[3 * f] >> triangles[3 * f + 1] >> triangles[3 * f + 2];
    if (n != 3)
    {
      throw std::runtime_error("PLY face is not a triangle");
    }
  }
  if (!in)
  {
    throw std::runtime_error("truncated PLY file " + path);
  }
}

/// Icosahedron subdivided `levels` times and projected on the sphere of
/// radius r about the origin (outward-facing triangles).
inline void IcoSphere(int levels, double r, std::vector<double>& points, std::vector<int>& triangles)
{
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> p = { { -1, t, 0 }, { 1, t, 0 }, { -1, -t, 0 }, { 1, -t, 0 },
    { 0, -1, t }, { 0, 1, t }, { 0, -1, -t }, { 0, 1, -t }, { t, 0, -1 }, { t, 0, 1 },
    { -t, 0, -1 }, { -t, 0, 1 } };
  std::vector<int> tri = { 0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4,
    11, 10, 2, 10, 7, 6, 7, 1, 8, 3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11,
    6, 2, 10, 8, 6, 7, 9, 8, 1 };
  for (auto& q : p)
  {
    q.normalize();
  }
  for (int level = 0; level < levels; ++level)
  {
    std::map<std::pair<int, int>, int> middle;
    auto mid = [&](int a, int b)
    {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = middle.find(key);
      if (it != middle.end())
      {
        return it->second;
      }
      p.push_back((p[a] + p[b]).normalized());
      return middle[key] = static_cast<int>(p.size()) - 1;
    };
    std::vector<int> next;
    for (std::size_t f = 0; f < tri.size(); f += 3)
    {
      const int a = tri[f], b = tri[f + 1], c = tri[f + 2];
      const int ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      next.insert(next.end(), { a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca });
    }
    tri.swap(next);
  }
  points.clear();
  for (const auto& q : p)
  {
    points.insert(points.end(), { r * q[0], r * q[1], r * q[2] });
  }
  triangles = tri;
}

} // namespace testing
} // namespace translucency
