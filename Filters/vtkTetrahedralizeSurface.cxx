#include "vtkTetrahedralizeSurface.h"

#include "vtkTranslucencyDispatch.h"
#include "Error.h"
#include "ResourceLimits.h"
#include "Strings.h"
#include "SurfaceIntersections.h"
#include "TetMesh.h"
#include "TranslucencyChildProcess.h"
#include "TranslucencyHxtMesher.h"
#include "vtkTranslucencyMeshConversion.h"
#include "vtkTranslucencyOutputGuard.h"

#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkIdTypeArray.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkGenericCell.h>
#include <vtkStaticCellLocator.h>
#include <vtkStaticCleanPolyData.h>
#include <vtkUnstructuredGrid.h>

#include <tetgen.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <sstream>
#include <vector>


vtkStandardNewMacro(vtkTetrahedralizeSurface);

namespace
{
/// A triangle surface after checks, ids 0..n-1.
struct Surface
{
  std::vector<double> Points;
  std::vector<std::array<vtkIdType, 3>> Triangles;
};

std::string FormatPoint(const double* p)
{
  std::ostringstream os;
  os << "(" << p[0] << ", " << p[1] << ", " << p[2] << ")";
  return os.str();
}

/// Checks: triangles only, no degenerate triangle, every edge used exactly twice.
bool CheckSurface(vtkPolyData* input, Surface& surface, double& volume, std::string& error)
{
  if (!input || input->GetNumberOfPoints() == 0 || input->GetNumberOfPolys() == 0)
  {
    error = "the input surface is empty (no points or no polygons)";
    return false;
  }
  if (input->GetNumberOfStrips() > 0 || input->GetNumberOfLines() > 0)
  {
    error = "the input has triangle strips or lines: give a surface of triangles "
            "(vtkTriangleFilter converts strips and polygons)";
    return false;
  }
  const vtkIdType np = input->GetNumberOfPoints();
  surface.Points.resize(3 * np);
  for (vtkIdType i = 0; i < np; ++i)
  {
    input->GetPoint(i, &surface.Points[3 * i]);
    for (int k = 0; k < 3; ++k)
    {
      if (!std::isfinite(surface.Points[3 * i + k]))
      {
        error = "point " + std::to_string(i) + " has a non-finite coordinate";
        return false;
      }
    }
  }
  double bounds[6];
  input->GetBounds(bounds);
  const double diag = std::sqrt((bounds[1] - bounds[0]) * (bounds[1] - bounds[0]) +
    (bounds[3] - bounds[2]) * (bounds[3] - bounds[2]) + (bounds[5] - bounds[4]) * (bounds[5] - bounds[4]));
  const double minArea = 1e-12 * diag * diag;

  vtkCellArray* polys = input->GetPolys();
  auto it = vtk::TakeSmartPointer(polys->NewIterator());
  vtkIdType cellId = input->GetNumberOfVerts(); // polys follow verts in cell numbering
  std::vector<std::array<vtkIdType, 3>> edges; // (min, max, triangle)
  volume = 0.0;
  for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell(), ++cellId)
  {
    vtkIdType npts;
    const vtkIdType* ids;
    it->GetCurrentCell(npts, ids);
    if (npts != 3)
    {
      error = "cell " + std::to_string(cellId) + " is a polygon with " + std::to_string(npts) +
        " points: give a surface of triangles (vtkTriangleFilter triangulates it)";
      return false;
    }
    const double* a = &surface.Points[3 * ids[0]];
    const double* b = &surface.Points[3 * ids[1]];
    const double* c = &surface.Points[3 * ids[2]];
    double u[3], v[3], n[3];
    for (int k = 0; k < 3; ++k)
    {
      u[k] = b[k] - a[k];
      v[k] = c[k] - a[k];
    }
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
    const double area = 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(area > minArea))
    {
      error = "triangle " + std::to_string(cellId) + " is degenerate (area " +
        translucency::FormatNumber(area) + " mm^2) at " + FormatPoint(a);
      return false;
    }
    volume += (a[0] * n[0] + a[1] * n[1] + a[2] * n[2]) / 6.0; // divergence theorem
    const vtkIdType tri = static_cast<vtkIdType>(surface.Triangles.size());
    surface.Triangles.push_back({ ids[0], ids[1], ids[2] });
    for (int e = 0; e < 3; ++e)
    {
      vtkIdType p = ids[e], q = ids[(e + 1) % 3];
      edges.push_back({ std::min(p, q), std::max(p, q), tri });
    }
  }
  std::sort(edges.begin(), edges.end());
  size_t open = 0, nonManifold = 0;
  std::string firstOpen, firstNonManifold;
  for (size_t i = 0; i < edges.size();)
  {
    size_t j = i;
    while (j < edges.size() && edges[j][0] == edges[i][0] && edges[j][1] == edges[i][1])
    {
      ++j;
    }
    const size_t uses = j - i;
    if (uses == 1 && open++ == 0)
    {
      firstOpen = FormatPoint(&surface.Points[3 * edges[i][0]]) + "-" +
        FormatPoint(&surface.Points[3 * edges[i][1]]);
    }
    if (uses > 2 && nonManifold++ == 0)
    {
      firstNonManifold = FormatPoint(&surface.Points[3 * edges[i][0]]) + "-" +
        FormatPoint(&surface.Points[3 * edges[i][1]]) + " (" + std::to_string(uses) + " triangles)";
    }
    i = j;
  }
  if (nonManifold > 0)
  {
    error = "surface is not manifold: " + std::to_string(nonManifold) +
      " edges are shared by more than two triangles, first at " + firstNonManifold;
    return false;
  }
  if (open > 0)
  {
    error = "surface is not closed: " + std::to_string(open) + " boundary edges, first at " +
      firstOpen + " (fill the holes, e.g. with vtkFillHolesFilter)";
    return false;
  }
  volume = std::abs(volume);
  // A closed surface lying in a plane (or enclosing next to nothing) would
  // make TetGen abort (an assertion on the flat bounding box), not throw.
  const double extent[3] = { bounds[1] - bounds[0], bounds[3] - bounds[2], bounds[5] - bounds[4] };
  if (!(std::min({ extent[0], extent[1], extent[2] }) > 1e-9 * diag) ||
    !(volume > 1e-12 * diag * diag * diag))
  {
    std::ostringstream os;
    os << "the surface encloses no volume (" << volume << " mm^3; bounding box " << extent[0]
       << " x " << extent[1] << " x " << extent[2] << " mm): it is flat";
    error = os.str();
    return false;
  }
  return true;
}

std::string TetGenErrorText(int code)
{
  switch (code)
  {
    case 1:
      return "out of memory";
    case 2:
      return "internal error";
    case 3:
      return "the surface self-intersects";
    case 4:
      return "the surface has a very small feature relative to the requested tet size";
    case 5:
      return "two surface facets are nearly coplanar and overlapping";
    case 10:
      return "the surface has duplicate or nearly coincident vertices";
    default:
      return "error code " + std::to_string(code);
  }
}

/// What the callers read of TetGen's output, sent from the child: the
/// points, the tets and the intersecting faces of a -d pass.
struct TetGenOutputHeader
{
  int Status = 0; ///< 0: done; else TetGen's error code (its `throw int`)
  int FirstNumber = 0;
  int NumberOfPoints = 0;
  int NumberOfCorners = 0;
  int NumberOfTetrahedra = 0;
  int NumberOfTriFaces = 0;
};

/**
 * tetrahedralize() in a child process (fork), its output sent back through
 * a pipe. TetGen 1.5.0 (the Debian/Ubuntu libtet) stops with a failed
 * assertion (SIGABRT) or a segmentation fault on some surfaces that pass
 * every check before it: `make fuzz-long` found a bunny with one vertex moved
 * 10 m away (a needle) that aborted the whole program in
 * tetgenmesh::fillcavity (issue 34). In a child, such a crash is a clean
 * error naming the signal; TetGen's own errors (`throw int`) come back as
 * their codes. Returns false with `error` set on either.
 */
bool IsolatedTetrahedralize(char* switches, tetgenio* in, tetgenio* out, tetgenio* background,
  std::string& error)
{
  using translucency::ReadAll;
  using translucency::WriteAll;
  // The child: TetGen, then its output down the pipe.
  auto work = [&](int fd) {
    TetGenOutputHeader header;
    try
    {
      tetrahedralize(switches, in, out, nullptr, background);
    }
    catch (int code)
    {
      header.Status = code == 0 ? -1 : code;
    }
    catch (...)
    {
      header.Status = 1; // std::bad_alloc from TetGen's new
    }
    if (header.Status == 0)
    {
      header.FirstNumber = out->firstnumber;
      header.NumberOfPoints = out->pointlist ? out->numberofpoints : 0;
      header.NumberOfCorners = out->numberofcorners;
      header.NumberOfTetrahedra = out->tetrahedronlist ? out->numberoftetrahedra : 0;
      header.NumberOfTriFaces = out->trifacelist ? out->numberoftrifaces : 0;
    }
    bool ok = WriteAll(fd, &header, sizeof(header));
    ok = ok && WriteAll(fd, out->pointlist, sizeof(REAL) * 3 * size_t(header.NumberOfPoints));
    ok = ok &&
      WriteAll(fd, out->tetrahedronlist,
        sizeof(int) * size_t(header.NumberOfCorners) * size_t(header.NumberOfTetrahedra));
    return ok && WriteAll(fd, out->trifacelist, sizeof(int) * 3 * size_t(header.NumberOfTriFaces));
  };
  TetGenOutputHeader header;
  auto read = [&](int fd) {
    bool received = ReadAll(fd, &header, sizeof(header));
    if (!received || header.Status != 0)
    {
      return received;
    }
    const bool sane = header.NumberOfPoints >= 0 && header.NumberOfTetrahedra >= 0 &&
      header.NumberOfTriFaces >= 0 && header.NumberOfCorners >= 0 && header.NumberOfCorners <= 10;
    received = sane;
    out->firstnumber = header.FirstNumber;
    out->numberofpoints = header.NumberOfPoints;
    out->numberofcorners = header.NumberOfCorners;
    out->numberoftetrahedra = header.NumberOfTetrahedra;
    out->numberoftrifaces = header.NumberOfTriFaces;
    if (received && header.NumberOfPoints > 0)
    {
      out->pointlist = new REAL[3 * size_t(header.NumberOfPoints)];
      received = ReadAll(fd, out->pointlist, sizeof(REAL) * 3 * size_t(header.NumberOfPoints));
    }
    const size_t corners = size_t(header.NumberOfCorners) * size_t(header.NumberOfTetrahedra);
    if (received && corners > 0)
    {
      out->tetrahedronlist = new int[corners];
      received = ReadAll(fd, out->tetrahedronlist, sizeof(int) * corners);
    }
    if (received && header.NumberOfTriFaces > 0)
    {
      out->trifacelist = new int[3 * size_t(header.NumberOfTriFaces)];
      received = ReadAll(fd, out->trifacelist, sizeof(int) * 3 * size_t(header.NumberOfTriFaces));
    }
    return received;
  };
  const translucency::ChildOutcome outcome = translucency::RunInChildProcess(work, read);
  if (!outcome.Started)
  {
    error = "TetGen could not be started (" + outcome.StartError + ")";
    return false;
  }
  if (outcome.Signal != 0)
  {
    const int signal = outcome.Signal;
    error = "TetGen crashed on this surface (signal " + std::to_string(signal) + ", " +
      (signal == SIGABRT ? std::string("SIGABRT: one of TetGen 1.5.0's internal checks failed")
                         : signal == SIGSEGV ? std::string("SIGSEGV")
                                             : std::string(strsignal(signal))) +
      "): the surface may have a spike or nearly degenerate triangles; check it, or try "
      "another mesher (hxt)";
    return false;
  }
  if (outcome.Received && header.Status != 0)
  {
    error = "TetGen failed: " + TetGenErrorText(header.Status == -1 ? 0 : header.Status);
    return false;
  }
  if (!outcome.Received || outcome.ExitStatus != 0)
  {
    error = "TetGen stopped without handing back its result (exit status " +
      std::to_string(outcome.ExitStatus) + ")";
    return false;
  }
  return true;
}

/// The surface as TetGen's input: one triangle facet per triangle.
void FillTetGenInput(const Surface& surface, tetgenio& in)
{
  in.firstnumber = 0;
  in.numberofpoints = static_cast<int>(surface.Points.size() / 3);
  in.pointlist = new REAL[surface.Points.size()];
  std::copy(surface.Points.begin(), surface.Points.end(), in.pointlist);
  in.numberoffacets = static_cast<int>(surface.Triangles.size());
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
      facet.polygonlist[0].vertexlist[k] = static_cast<int>(surface.Triangles[f][k]);
    }
  }
}

/// TetGen 1.5.0 (the Debian/Ubuntu libtet) crashes (SIGSEGV in
/// tetgenmesh::freememory) when meshing with -p stops on a self-intersecting
/// surface, instead of throwing its error code. So that error, the one a
/// user is most likely to hit, is detected beforehand with TetGen's -d
/// switch, which only reports the intersecting triangles and returns.
///
/// TetGen's -d pass can itself take minutes on a surface whose triangles
/// cross many others (a file whose vertices were shifted by one line), so an
/// edge piercing a triangle is looked for first through a BVH
/// (translucency::FindEdgeCrossing, O(E log T)); -d then finds the rest
/// (coplanar overlaps, contacts at vertices).
bool CheckSelfIntersections(const Surface& surface, std::string& error)
{
  {
    std::vector<int> triangles(3 * surface.Triangles.size());
    for (size_t t = 0; t < surface.Triangles.size(); ++t)
    {
      for (int k = 0; k < 3; ++k)
      {
        triangles[3 * t + k] = static_cast<int>(surface.Triangles[t][k]);
      }
    }
    translucency::EdgeCrossing crossing;
    try
    {
      if (translucency::FindEdgeCrossing(surface.Points, triangles, crossing))
      {
        error = "the surface intersects itself: the edge " +
          FormatPoint(&surface.Points[3 * crossing.EdgePoints[0]]) + "-" +
          FormatPoint(&surface.Points[3 * crossing.EdgePoints[1]]) + " crosses triangle " +
          std::to_string(crossing.Triangle) + " at " + FormatPoint(crossing.Point);
        return false;
      }
    }
    catch (const translucency::Error& e)
    {
      error = e.what();
      return false;
    }
  }
  tetgenio in, out;
  FillTetGenInput(surface, in);
  char switches[] = "dQ";
  if (!IsolatedTetrahedralize(switches, &in, &out, nullptr, error))
  {
    return false;
  }
  if (out.numberoftrifaces > 0)
  {
    std::ostringstream os;
    os << "the surface intersects itself: " << out.numberoftrifaces
       << " triangles cross other triangles";
    const int v = out.trifacelist[0] - out.firstnumber;
    if (out.pointlist && v >= 0 && v < out.numberofpoints)
    {
      os << ", first near " << FormatPoint(&out.pointlist[3 * v]);
    }
    error = os.str();
    return false;
  }
  return true;
}

/// Run TetGen with the given switches; fills points and tets (0-based).
/// With sizing > 0 (and an 'm' among the switches), sizing is TetGen's
/// target edge length at every input point (its -m sizing function, which
/// it interpolates to the points it adds).
/// With background (a tet mesh whose points carry pointmtrlist), TetGen's -m
/// sizing function is interpolated from it instead (tetrahedralize's bgmin).
bool RunTetGen(const Surface& surface, const std::string& switches, std::vector<double>& points,
  std::vector<int>& tets, std::string& error, double sizing = 0.0,
  tetgenio* background = nullptr)
{
  tetgenio in, out;
  FillTetGenInput(surface, in);
  if (sizing > 0)
  {
    in.numberofpointmtrs = 1;
    in.pointmtrlist = new REAL[in.numberofpoints];
    std::fill(in.pointmtrlist, in.pointmtrlist + in.numberofpoints, sizing);
  }
  std::vector<char> sw(switches.begin(), switches.end());
  sw.push_back('\0');
  if (!IsolatedTetrahedralize(sw.data(), &in, &out, background, error))
  {
    return false;
  }
  if (out.numberoftetrahedra <= 0)
  {
    error = "TetGen produced no tetrahedra";
    return false;
  }
  points.assign(out.pointlist, out.pointlist + 3 * static_cast<size_t>(out.numberofpoints));
  const int corners = out.numberofcorners;
  tets.resize(4 * static_cast<size_t>(out.numberoftetrahedra));
  for (int t = 0; t < out.numberoftetrahedra; ++t)
  {
    for (int k = 0; k < 4; ++k)
    {
      tets[4 * t + k] = out.tetrahedronlist[corners * t + k] - out.firstnumber;
    }
  }
  return true;
}

/// The graded sizing function h(d) = min(h, h / g + (1 - 1 / g) d) as a
/// TetGen background mesh: a coarse TetGen mesh of the surface (no quality
/// refinement, surface kept (-Y), volume bound of the regular tet of edge 2h)
/// whose points carry h(d), d the exact distance to the surface triangles.
/// TetGen interpolates h linearly inside each background tet.
bool BuildGradedBackground(const Surface& surface, double h, double g, tetgenio& background,
  std::string& error)
{
  std::vector<double> points;
  std::vector<int> tets;
  std::ostringstream os;
  os.precision(17);
  const double coarseVolume = std::pow(2.0 * h, 3) / (6.0 * std::sqrt(2.0));
  os << "pYa" << coarseVolume << "zQ";
  if (!RunTetGen(surface, os.str(), points, tets, error))
  {
    error = "the background mesh of the graded sizing: " + error;
    return false;
  }
  vtkNew<vtkPoints> surfacePoints;
  surfacePoints->SetDataTypeToDouble();
  const vtkIdType numSurfacePoints = static_cast<vtkIdType>(surface.Points.size() / 3);
  surfacePoints->SetNumberOfPoints(numSurfacePoints);
  for (vtkIdType i = 0; i < numSurfacePoints; ++i)
  {
    surfacePoints->SetPoint(i, &surface.Points[3 * i]);
  }
  vtkNew<vtkCellArray> triangles;
  for (const auto& t : surface.Triangles)
  {
    triangles->InsertNextCell(3, t.data());
  }
  vtkNew<vtkPolyData> polyData;
  polyData->SetPoints(surfacePoints);
  polyData->SetPolys(triangles);
  vtkNew<vtkStaticCellLocator> locator;
  locator->SetDataSet(polyData);
  locator->BuildLocator();

  const int numPoints = static_cast<int>(points.size() / 3);
  background.firstnumber = 0;
  background.numberofpoints = numPoints;
  background.pointlist = new REAL[points.size()];
  std::copy(points.begin(), points.end(), background.pointlist);
  background.numberofpointmtrs = 1;
  background.pointmtrlist = new REAL[numPoints];
  vtkNew<vtkGenericCell> cell;
  for (int i = 0; i < numPoints; ++i)
  {
    double closest[3], distance2 = 0.0;
    vtkIdType cellId = -1;
    int subId = 0;
    locator->FindClosestPoint(&points[3 * i], closest, cell, cellId, subId, distance2);
    background.pointmtrlist[i] =
      std::min(h, h / g + (1.0 - 1.0 / g) * std::sqrt(std::max(distance2, 0.0)));
  }
  background.numberofcorners = 4;
  background.numberoftetrahedra = static_cast<int>(tets.size() / 4);
  background.tetrahedronlist = new int[tets.size()];
  std::copy(tets.begin(), tets.end(), background.tetrahedronlist);
  return true;
}

/// What the meshing phases below read of the filter's settings.
struct MeshSettings
{
  std::string Mesher;         ///< lower case: "tetgen" or "hxt"
  double Grading = 0.0;       ///< GradingFactor: 0 (off) or in [1, 8]
  bool UniformSizing = false;
  vtkIdType TargetNumberOfTets = 0;
  double MaxTetVolume = 0.0;  ///< mm^3
  double MemoryLimit = 0.0;   ///< GiB; 0: the default limit
  double Quality = 1.414;
  int NumberOfThreads = 0;
  bool HxtOptimization = false;
};

std::size_t MemoryLimitBytes(double gib)
{
  return gib > 0 ? static_cast<std::size_t>(std::min(gib * 1073741824.0, 1.8e19))
                 : translucency::GetDefaultMemoryLimit();
}

/// The error for a mesher this build does not have (`name` as the user wrote it).
std::string UnknownMesherError(const std::string& mesher, const std::string& name)
{
  if (mesher == "hxt")
  {
    translucency::HxtMesherOptions none;
    std::vector<double> p;
    std::vector<int> t;
    std::string message;
    translucency::RunHxtMesher({}, {}, none, p, t, message); // the build's message
    return "mesher 'hxt': " + message;
  }
  return "unknown mesher '" + name + "': use tetgen or hxt";
}

/// The grading factor: off (0) or in [1, 8], tetgen only, not with
/// UniformSizing. Returns "" when the settings are fine.
std::string CheckGrading(const MeshSettings& s)
{
  const double grading = s.Grading;
  std::ostringstream msg;
  if (grading == 0.0)
  {
    return std::string();
  }
  if (!std::isfinite(grading) || grading < 1.0 || grading > 8.0)
  {
    msg << "GradingFactor " << grading
        << " is out of range: use 0 (off: the mesher's own grading) or a ratio of "
           "interior to surface edge length from 1 (uniform) to 8";
  }
  else if (s.UniformSizing)
  {
    msg << "GradingFactor " << grading
        << " and UniformSizing are both set: uniform sizing is GradingFactor 1; set one of them";
  }
  else if (s.Mesher != "tetgen")
  {
    msg << "GradingFactor is available with the tetgen mesher only (mesher '" << s.Mesher
        << "'): use UniformSizing with hxt, or mesher tetgen";
  }
  return msg.str();
}

/// The surface the mesher gets: coordinates and ids checked first
/// (vtkStaticCleanPolyData crashes on infinite or huge coordinates and on
/// point ids out of range), coincident points merged (STL/OBJ files often
/// repeat them), then closed, manifold and free of self-intersections.
bool PrepareSurface(vtkPolyData* input, Surface& surface, double& volume, std::string& error)
{
  if (input && input->GetNumberOfCells() > 0 &&
    !vtkTranslucency::CheckSurfacePointsAndIds(
      input, vtkTetrahedralizeSurface::MaxCoordinate, error))
  {
    return false;
  }
  vtkNew<vtkStaticCleanPolyData> clean;
  vtkNew<vtkPolyData> copy;
  if (input)
  {
    copy->ShallowCopy(input);
  }
  clean->SetInputData(copy);
  clean->SetTolerance(0.0);
  clean->ConvertPolysToLinesOff();
  clean->ConvertLinesToPointsOff();
  clean->ConvertStripsToPolysOff();
  if (input && input->GetNumberOfPoints() > 0)
  {
    clean->Update();
  }
  return CheckSurface(input && input->GetNumberOfPoints() > 0 ? clean->GetOutput() : input,
           surface, volume, error) &&
    CheckSelfIntersections(surface, error);
}

/// The size guard: estimate the tet count before the mesher allocates it.
/// Throws translucency::Error when it does not fit.
void CheckSize(const MeshSettings& s, double volume)
{
  const double tets = s.TargetNumberOfTets > 0
    ? static_cast<double>(s.TargetNumberOfTets)
    : (s.MaxTetVolume > 0 ? volume / s.MaxTetVolume : 0.0);
  std::ostringstream what;
  what << "about " << translucency::FormatNumber(tets) << " tets ("
       << (s.TargetNumberOfTets > 0
              ? "TargetNumberOfTets"
              : "enclosed volume " + translucency::FormatNumber(volume) + " mm^3 / MaxTetVolume " +
                translucency::FormatNumber(s.MaxTetVolume) + " mm^3")
       << ")";
  translucency::CheckMemory(what.str(), tets * 400.0, MemoryLimitBytes(s.MemoryLimit),
    "ask for fewer tets (a smaller target or a larger maximum volume; filter: MemoryLimit GiB)");
  if (tets * 4.0 >= static_cast<double>(std::numeric_limits<int>::max()))
  {
    throw translucency::Error(what.str() + " are more than the 32-bit indices hold");
  }
}

/// The diagonal of the surface's bounding box (mm).
double BoundingDiagonal(const Surface& surface)
{
  double lo[3] = { VTK_DOUBLE_MAX, VTK_DOUBLE_MAX, VTK_DOUBLE_MAX };
  double hi[3] = { -VTK_DOUBLE_MAX, -VTK_DOUBLE_MAX, -VTK_DOUBLE_MAX };
  for (size_t i = 0; i < surface.Points.size(); ++i)
  {
    lo[i % 3] = std::min(lo[i % 3], surface.Points[i]);
    hi[i % 3] = std::max(hi[i % 3], surface.Points[i]);
  }
  return std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
    (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

/// The A k of the graded layer (A the surface area, k = g (g + 1) / 2 - 1;
/// see FirstParameter); 0 without grading.
double GradedLayer(const Surface& surface, double grading)
{
  if (grading <= 0.0)
  {
    return 0.0;
  }
  double area = 0.0;
  for (const auto& t : surface.Triangles)
  {
    const double* a = &surface.Points[3 * t[0]];
    const double* b = &surface.Points[3 * t[1]];
    const double* c = &surface.Points[3 * t[2]];
    const double u[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
    const double v[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
    const double n[3] = { u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
      u[0] * v[1] - u[1] * v[0] };
    area += 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  }
  return area * (grading * (grading + 1.0) / 2.0 - 1.0);
}

/// The hxt mesher's surface refinement: longest-edge bisection leaves edges
/// between half and all of the bound, so a bound of this factor times the
/// interior edge length h gives surface edges of about h on average.
constexpr double HxtSurfaceEdgeFactor = 1.35;

/// One run of the mesher for a size `parameter`: TetGen's volume bound -a
/// (graded: the edge length of its background) or edge length (uniform, -m);
/// HXT's edge length. 0: none (`diag` the surface's bounding-box diagonal).
bool RunMesher(const MeshSettings& s, const Surface& surface, double diag, double parameter,
  std::vector<double>& points, std::vector<int>& tets, std::string& error,
  double hxtSurfaceEdge = 0.0)
{
  if (s.Mesher == "tetgen" && s.Grading > 0.0)
  {
    const double h = parameter > 0 ? parameter : diag / 10.0;
    tetgenio background;
    if (!BuildGradedBackground(surface, h, s.Grading, background, error))
    {
      return false;
    }
    std::ostringstream os;
    os.precision(17);
    os << "pq" << s.Quality << "mzQ";
    return RunTetGen(surface, os.str(), points, tets, error, h / s.Grading, &background);
  }
  if (s.Mesher == "tetgen")
  {
    std::ostringstream os;
    os.precision(17);
    os << "pq" << s.Quality;
    double sizing = 0.0;
    if (s.UniformSizing)
    {
      sizing = parameter;
      if (s.TargetNumberOfTets == 0 && s.MaxTetVolume > 0)
      {
        os << "a" << s.MaxTetVolume;
      }
      if (sizing > 0)
      {
        os << "m";
      }
    }
    else if (parameter > 0)
    {
      os << "a" << parameter;
    }
    os << "zQ";
    return RunTetGen(surface, os.str(), points, tets, error, sizing);
  }
  std::vector<int> triangles(3 * surface.Triangles.size());
  for (size_t t = 0; t < surface.Triangles.size(); ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      triangles[3 * t + k] = static_cast<int>(surface.Triangles[t][k]);
    }
  }
  translucency::HxtMesherOptions options;
  options.MeshSize = parameter > 0 ? parameter : diag;
  options.RemeshSurface = s.UniformSizing;
  // HXT keeps the surface it gets: the input surface is refined to about
  // the interior edge length first, or a coarse surface grades into slivers
  // (Documentation/Performance.md, "Tetrahedralisers").
  options.SurfaceEdgeLength = hxtSurfaceEdge;
  options.Threads = s.NumberOfThreads;
  options.Optimize = s.HxtOptimization;
  return translucency::RunHxtMesher(surface.Points, triangles, options, points, tets, error);
}

/// How the tet count depends on the size parameter. Measured counts (bunny,
/// sphere): TetGen -q1.414 -a: N falls like a^-0.8 and a = 2.5 V/N gives
/// about N at N = 1e6; TetGen -m h: N ~ 5 V / h^3 (5 mm sphere); HXT with
/// edge length h: N ~ 5.5 V / h^3 (bunny, sphere).
struct CountModel
{
  explicit CountModel(const MeshSettings& s)
    : EdgeLength(s.Mesher == "hxt" || s.UniformSizing || s.Grading > 0.0)
    , CountConstant(s.Mesher == "hxt" ? 5.5 : 5.0)
    , Exponent(EdgeLength ? 1.0 / 3.0 : 1.0 / 0.8)
  {
  }
  bool EdgeLength;      ///< the parameter is an edge length (else a volume bound)
  double CountConstant; ///< c of N ~ c V / h^3
  double Exponent;      ///< parameter ~ N^-Exponent
};

/// The first run's size parameter from TargetNumberOfTets or MaxTetVolume
/// (0: the mesher's own size). Throws translucency::Error when a graded
/// mesh would not fit in memory.
double FirstParameter(const MeshSettings& s, const CountModel& model, double volume,
  double gradedLayer)
{
  // The edge length of the regular tet of volume v.
  auto regularEdge = [](double v) { return std::cbrt(6.0 * std::sqrt(2.0) * v); };
  double parameter = 0.0;
  if (s.TargetNumberOfTets > 0)
  {
    const double target = static_cast<double>(s.TargetNumberOfTets);
    parameter = model.EdgeLength ? std::cbrt(model.CountConstant * volume / target)
                                 : 2.5 * volume / target;
    // Graded: the transition layer adds about A (g (g + 1) / 2 - 1) / h^2
    // cells (the integral of 1/h(d)^3 - 1/h^3 over the layer, A the surface
    // area): solve N = c (V / h^3 + A k / h^2) for h by fixed point.
    for (int it = 0; s.Grading > 0.0 && it < 30; ++it)
    {
      parameter = std::cbrt(model.CountConstant * (volume + gradedLayer * parameter) / target);
    }
  }
  else if (s.MaxTetVolume > 0)
  {
    parameter = model.EdgeLength ? regularEdge(s.MaxTetVolume) : s.MaxTetVolume;
    if (s.Grading > 0.0)
    {
      // The size guard counted the volume only: add the graded layer.
      const double tets = model.CountConstant *
        (volume / std::pow(parameter, 3) + gradedLayer / (parameter * parameter));
      translucency::CheckMemory("about " + translucency::FormatNumber(tets) +
          " tets (MaxTetVolume with GradingFactor " + translucency::FormatNumber(s.Grading) + ")",
        tets * 400.0, MemoryLimitBytes(s.MemoryLimit),
        "ask for fewer tets (a larger maximum volume or a smaller GradingFactor; filter: "
        "MemoryLimit GiB)");
    }
  }
  return parameter;
}

/// How far a count may miss TargetNumberOfTets before the filter says why
/// (vtkTetrahedralizeSurface.h: "within 25 %").
constexpr double TargetTolerance = 0.25;

/// A first run this many times above the target meshes the surface's floor
/// (its coarsest mesh, the cheapest run) next. On the bundled bunny (3,674
/// triangles, a floor of 45,113 tets) TetGen ran 3 times for a target of
/// 3,000 or 5,000 and 4 times for 30,000 (first run, corrections, the floor
/// for the warning), now twice; a target the floor does not bind pays the
/// floor run (bunny at 50,000: 4 runs instead of 3).
constexpr double FloorFirstRatio = 2.0;

/// hxt with uniform sizing re-meshes the surface: no floor from its triangles.
bool RemeshesSurface(const MeshSettings& s)
{
  return s.Mesher == "hxt" && s.UniformSizing;
}

/// The mesher's runs: one for the first size parameter, a second one
/// correcting the parameter when the count misses TargetNumberOfTets by more
/// than 15 %, and a third on the secant of log N against log h through the
/// two when the second still misses (the count is not a power of the size:
/// graded layers grow as h^-2, TetGen's quality bound refines near the
/// surface). A first run more than FloorFirstRatio times the target is
/// followed by the surface's coarsest mesh instead (`floor`: its count, 0
/// when not run), which ends the search when it is itself too many.
/// `progress` reports the filter's progress. Throws translucency::Error as
/// FirstParameter.
bool MeshToTarget(const MeshSettings& s, const Surface& surface, double volume,
  const std::function<void(double)>& progress, std::vector<double>& points,
  std::vector<int>& tets, std::string& error, size_t& floor)
{
  floor = 0;
  const double diag = BoundingDiagonal(surface);
  const CountModel model(s);
  double parameter = FirstParameter(s, model, volume, GradedLayer(surface, s.Grading));
  // hxt: the surface refinement is that of the first size for every run,
  // so that the count follows the interior size smoothly (bisection
  // refines a surface of similar edges in steps of 2x, all at once).
  const double hxtSurfaceEdge = parameter > 0 ? HxtSurfaceEdgeFactor * parameter : 0.0;
  if (!RunMesher(s, surface, diag, parameter, points, tets, error, hxtSurfaceEdge))
  {
    return false;
  }
  if (s.TargetNumberOfTets <= 0)
  {
    return true;
  }
  const double target = static_cast<double>(s.TargetNumberOfTets);
  const double ratio = static_cast<double>(tets.size() / 4) / target;
  if (std::abs(ratio - 1.0) <= 0.15)
  {
    return true;
  }
  progress(0.5);
  if (ratio > FloorFirstRatio && !RemeshesSurface(s))
  {
    // Far too many tets: the surface's resolution is the likely floor. Its
    // coarsest mesh (no size bound) is what ExplainMissedTarget would run:
    // run it now, and when it is itself above the tolerance, stop there
    // (a correction run could not come nearer).
    std::vector<double> floorPoints;
    std::vector<int> floorTets;
    if (!RunMesher(s, surface, diag, 0.0, floorPoints, floorTets, error))
    {
      return false;
    }
    floor = floorTets.size() / 4;
    if (static_cast<double>(floor) > (1.0 + TargetTolerance) * target)
    {
      if (floor < tets.size() / 4) // nearer the target (equal counts: the first run's mesh)
      {
        points.swap(floorPoints);
        tets.swap(floorTets);
      }
      return true;
    }
    // Otherwise the size bound decides, as without the floor run: a mesh
    // of the target's size, not the floor's coarse interior, even when the
    // floor's count is near the target (TestPaint's 2,000-tet sphere).
  }
  const double firstParameter = parameter;
  parameter *= std::pow(ratio, model.Exponent);
  std::vector<double> firstPoints;
  std::vector<int> firstTets;
  firstPoints.swap(points);
  firstTets.swap(tets);
  if (!RunMesher(s, surface, diag, parameter, points, tets, error, hxtSurfaceEdge))
  {
    return false;
  }
  const double ratio2 = static_cast<double>(tets.size() / 4) / target;
  // The first run was closer (the second overshot): keep it.
  if (std::abs(std::log(ratio)) < std::abs(std::log(ratio2)))
  {
    points.swap(firstPoints);
    tets.swap(firstTets);
  }
  if (std::abs(ratio2 - 1.0) > 0.15 && std::abs(ratio2 - ratio) > 1e-3)
  {
    progress(0.7);
    const double slope = std::log(ratio2 / ratio) / std::log(parameter / firstParameter);
    if (std::isfinite(slope) && slope < 0.0)
    {
      const double best = std::min(std::abs(std::log(ratio)), std::abs(std::log(ratio2)));
      std::vector<double> thirdPoints;
      std::vector<int> thirdTets;
      if (!RunMesher(s, surface, diag, parameter * std::exp(-std::log(ratio2) / slope),
            thirdPoints, thirdTets, error, hxtSurfaceEdge))
      {
        return false;
      }
      const double ratio3 = static_cast<double>(thirdTets.size() / 4) / target;
      if (std::abs(std::log(ratio3)) < best)
      {
        points.swap(thirdPoints);
        tets.swap(thirdTets);
      }
    }
  }
  return true;
}

/**
 * Why a count missed TargetNumberOfTets by more than TargetTolerance, and
 * what to do, or "" when it did not. Too many tets: the mesher's coarsest
 * mesh of this surface (its own size, no bound) is run; when it is itself
 * above the tolerance, the surface's resolution is the floor (TetGen keeps
 * every input triangle and refines near them for its quality bound).
 */
std::string ExplainMissedTarget(
  const MeshSettings& s, const Surface& surface, size_t made, size_t knownFloor)
{
  const double target = static_cast<double>(s.TargetNumberOfTets);
  if (s.TargetNumberOfTets <= 0 || std::abs(static_cast<double>(made) / target - 1.0) <= TargetTolerance)
  {
    return std::string();
  }
  std::ostringstream why;
  why << "TargetNumberOfTets " << s.TargetNumberOfTets << ": the mesh has " << made
      << " tets (" << std::showpos
      << std::lround(100.0 * (static_cast<double>(made) - target) / target) << std::noshowpos
      << " %, more than " << std::lround(100 * TargetTolerance) << " % off). ";
  std::vector<double> points;
  std::vector<int> tets;
  std::string error;
  if (static_cast<double>(made) > target && !RemeshesSurface(s) &&
    (knownFloor > 0 ||
      RunMesher(s, surface, BoundingDiagonal(surface), 0.0, points, tets, error)))
  {
    const size_t floor = knownFloor > 0 ? knownFloor : tets.size() / 4;
    if (static_cast<double>(floor) > (1.0 + TargetTolerance) * target)
    {
      why << "The input surface's resolution sets the floor: the " << s.Mesher
          << " mesher keeps its " << surface.Triangles.size()
          << " triangles (it may split them, never merges them), and the coarsest mesh it "
             "makes of this surface has "
          << floor
          << " tets. For fewer tets, decimate the surface first (ParaView: Decimate; VTK: "
             "vtkQuadricDecimation)";
      if (vtkTetrahedralizeSurface::HasMesher("hxt"))
      {
        why << ", or let the hxt mesher re-mesh it (Mesher hxt with UniformSizing; CLI: "
               "--mesher hxt --uniform-size)";
      }
      why << ".";
      return why.str();
    }
  }
  why << "The " << s.Mesher
      << " mesher's count does not follow its size bound closely on this surface; set the "
         "size directly with MaxTetVolume (CLI: --max-tet-volume) to choose it.";
  return why.str();
}

/// The output grid: the mesher's points and tets in Morton order (or as
/// they are), every tet positively oriented as VTK wants it.
void BuildOutput(const std::vector<double>& points, const std::vector<int>& tets,
  bool spatialReordering, vtkUnstructuredGrid* output)
{
  const size_t numPoints = points.size() / 3;
  const size_t numTets = tets.size() / 4;
  std::vector<int> pointOrder, tetOrder;
  if (spatialReordering)
  {
    translucency::TetMesh::ComputeSpatialOrder(points, tets, pointOrder, tetOrder);
  }
  else
  {
    pointOrder.resize(numPoints);
    tetOrder.resize(numTets);
    for (size_t i = 0; i < numPoints; ++i)
    {
      pointOrder[i] = static_cast<int>(i);
    }
    for (size_t t = 0; t < numTets; ++t)
    {
      tetOrder[t] = static_cast<int>(t);
    }
  }
  std::vector<vtkIdType> newId(numPoints);
  vtkNew<vtkPoints> outPoints;
  outPoints->SetDataTypeToDouble();
  outPoints->SetNumberOfPoints(static_cast<vtkIdType>(numPoints));
  for (size_t k = 0; k < numPoints; ++k)
  {
    newId[pointOrder[k]] = static_cast<vtkIdType>(k);
    outPoints->SetPoint(static_cast<vtkIdType>(k), &points[3 * pointOrder[k]]);
  }
  vtkNew<vtkIdTypeArray> connectivity;
  connectivity->SetNumberOfValues(static_cast<vtkIdType>(4 * numTets));
  vtkNew<vtkIdTypeArray> offsets;
  offsets->SetNumberOfValues(static_cast<vtkIdType>(numTets + 1));
  for (size_t k = 0; k < numTets; ++k)
  {
    const int* t = &tets[4 * static_cast<size_t>(tetOrder[k])];
    vtkIdType ids[4] = { newId[t[0]], newId[t[1]], newId[t[2]], newId[t[3]] };
    // VTK's positive orientation: (p1-p0) x (p2-p0) . (p3-p0) > 0.
    const double* p0 = &points[3 * t[0]];
    const double* p1 = &points[3 * t[1]];
    const double* p2 = &points[3 * t[2]];
    const double* p3 = &points[3 * t[3]];
    double a[3], b[3], c[3];
    for (int d = 0; d < 3; ++d)
    {
      a[d] = p1[d] - p0[d];
      b[d] = p2[d] - p0[d];
      c[d] = p3[d] - p0[d];
    }
    const double det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
      a[2] * (b[0] * c[1] - b[1] * c[0]);
    if (det < 0)
    {
      std::swap(ids[0], ids[1]);
    }
    for (int d = 0; d < 4; ++d)
    {
      connectivity->SetValue(static_cast<vtkIdType>(4 * k + d), ids[d]);
    }
    offsets->SetValue(static_cast<vtkIdType>(k), static_cast<vtkIdType>(4 * k));
  }
  offsets->SetValue(static_cast<vtkIdType>(numTets), static_cast<vtkIdType>(4 * numTets));
  vtkNew<vtkCellArray> cells;
  cells->SetData(offsets, connectivity);
  output->SetPoints(outPoints);
  output->SetCells(VTK_TETRA, cells);
}
}

//------------------------------------------------------------------------------
vtkTetrahedralizeSurface::vtkTetrahedralizeSurface() = default;

//------------------------------------------------------------------------------
int vtkTetrahedralizeSurface::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPolyData");
  return 1;
}

//------------------------------------------------------------------------------
int vtkTetrahedralizeSurface::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return vtkTranslucencyDispatch::RunFilter(this, request, inputVector, outputVector);
}

//------------------------------------------------------------------------------
int vtkTetrahedralizeSurface::RequestUpdateExtent(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  return vtkTranslucencyDispatch::UpdateExtent(this, request, inputVector, outputVector);
}

//------------------------------------------------------------------------------
vtkTranslucencyParallelPlan vtkTetrahedralizeSurface::PlanParallel(
  vtkInformationVector**, const vtkTranslucencyCommunicator&)
{
  return vtkTranslucencyParallelPlan::Gathered(
    vtkTranslucencyParallelPlan::GatherMode::RankZero, "TetGen is serial: the tets on rank 0 (follow with Redistribute DataSet)");
}

//------------------------------------------------------------------------------
int vtkTetrahedralizeSurface::RequestSerial(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkPolyData* input = vtkPolyData::GetData(inputVector[0]);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector);
  MeshSettings settings;
  settings.Mesher = translucency::ToLower(this->Mesher);
  settings.Grading = this->GradingFactor;
  settings.UniformSizing = this->UniformSizing;
  settings.TargetNumberOfTets = this->TargetNumberOfTets;
  settings.MaxTetVolume = this->MaxTetVolume;
  settings.MemoryLimit = this->MemoryLimit;
  settings.Quality = this->Quality;
  settings.NumberOfThreads = this->NumberOfThreads;
  settings.HxtOptimization = this->HxtOptimization;

  // 1. The settings: the mesher's name first (a wrong one fails before the
  // checks' work), then the grading factor.
  std::string error;
  if (!vtkTetrahedralizeSurface::HasMesher(settings.Mesher.c_str()))
  {
    error = UnknownMesherError(settings.Mesher, this->Mesher);
  }
  else
  {
    error = CheckGrading(settings);
  }
  // 2. The surface: checked, cleaned, closed, not self-intersecting.
  Surface surface;
  double volume = 0.0;
  if (!error.empty() || !PrepareSurface(input, surface, volume, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  this->UpdateProgress(0.05);
  // 3. The size guard, 4. the mesher's runs towards the target.
  std::vector<double> points;
  std::vector<int> tets;
  size_t floor = 0; // the coarsest mesh's count when MeshToTarget ran it
  try
  {
    CheckSize(settings, volume);
    if (!MeshToTarget(settings, surface, volume, [this](double p) { this->UpdateProgress(p); },
          points, tets, error, floor))
    {
      vtkErrorMacro(<< error);
      return 0;
    }
  }
  catch (const translucency::Error& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  // A count far from the target: a warning saying why and what to do.
  const std::string missed = ExplainMissedTarget(settings, surface, tets.size() / 4, floor);
  if (!missed.empty())
  {
    vtkWarningMacro(<< missed);
  }
  this->UpdateProgress(0.9);
  // 5. The output grid.
  BuildOutput(points, tets, this->SpatialReordering, output);
  this->UpdateProgress(1.0);
  return outputs.Succeed();
}

//------------------------------------------------------------------------------
void vtkTetrahedralizeSurface::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Quality: " << this->Quality << "\n";
  os << indent << "MaxTetVolume: " << this->MaxTetVolume << "\n";
  os << indent << "TargetNumberOfTets: " << this->TargetNumberOfTets << "\n";
  os << indent << "MemoryLimit: " << this->MemoryLimit << " GiB\n";
  os << indent << "SpatialReordering: " << this->SpatialReordering << "\n";
  os << indent << "Mesher: " << this->Mesher << "\n";
  os << indent << "UniformSizing: " << this->UniformSizing << "\n";
  os << indent << "GradingFactor: " << this->GradingFactor << "\n";
  os << indent << "NumberOfThreads: " << this->NumberOfThreads << "\n";
  os << indent << "HxtOptimization: " << this->HxtOptimization << "\n";
  os << indent << "ParallelPath: " << this->ParallelPath << "\n";
  os << indent << "ParallelPlan: " << this->ParallelPlan << "\n";
}

//------------------------------------------------------------------------------
bool vtkTetrahedralizeSurface::HasMesher(const char* name)
{
  const std::string mesher = translucency::ToLower(name ? name : "");
  return mesher == "tetgen" || (mesher == "hxt" && translucency::HasHxtMesher());
}
