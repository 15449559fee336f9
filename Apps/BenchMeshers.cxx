// `translucency bench --meshers`: TetGen and HXT side by side (BenchMeshers.h).

#include "BenchMeshers.h"

#include "MeshIO.h"
#include "Utilities.h"

#include "Error.h"
#include "TetMesh.h"
#include "TetQuality.h"

#include "vtkTetrahedralizeSurface.h"

#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>

#include "vtk_nlohmannjson.h"
#include VTK_NLOHMANN_JSON(json.hpp)

#include <omp.h>

#include <iomanip>
#include <iostream>
#include <sstream>

namespace translucency_app
{

int BenchMeshers(const MesherBenchOptions& o)
{
  using json = nlohmann::json;
  std::string error;
  vtkSmartPointer<vtkPolyData> surface;
  vtkSmartPointer<vtkUnstructuredGrid> grid;
  if (!ReadMesh(o.MeshPath, surface, grid, error))
    throw translucency::Error(error);
  if (!surface)
    throw translucency::Error("bench --meshers needs a surface mesh (.ply, .stl, .obj, .vtp)");

  // The rows of each size: {mesher, uniform sizing, hxt's optimisation pass}.
  struct Row
  {
    std::string Mesher;
    bool Uniform;
    bool Optimize;
  };
  std::vector<Row> rows = { { "tetgen", false, true } };
  const bool hxt = vtkTetrahedralizeSurface::HasMesher("hxt");
  if (hxt)
  {
    rows.push_back({ "hxt", false, true });
    rows.push_back({ "hxt", false, false });
  }
  else
    std::cout << "hxt: not in this build (no gmsh)\n";
  if (!o.GradedOnly)
  {
    rows.push_back({ "tetgen", true, true });
    if (hxt)
      rows.push_back({ "hxt", true, true });
  }
  std::cout << "threads: " << omp_get_max_threads() << ", runs per figure: " << o.Runs
            << " (median time; the mesh of the last run is measured)\n"
            << "min dihedral histogram: tets per 10-degree bin of their smallest dihedral "
               "angle, 0-10 ... 70-80 (%)\n\n";
  std::cout << "  target    mesher  sizing        tets   time(ms)   Mtets/s  min-dih  <5deg(%)  max-r/e  "
               "mean-r/e >1.414(%)  edge-cv  boundary-pts  histogram(%)\n";
  json results = json::array();
  for (double target : o.Tets)
  {
    for (const Row& row : rows)
    {
      {
        const std::string& mesher = row.Mesher;
        const bool uniform = row.Uniform;
        const std::string label = mesher == "hxt" && !row.Optimize ? "hxt-noopt" : mesher;
        std::vector<double> times;
        vtkSmartPointer<vtkUnstructuredGrid> last;
        for (int r = 0; r < o.Runs; ++r)
        {
          MessageCollector messages;
          vtkNew<vtkTetrahedralizeSurface> tetra;
          messages.Watch(tetra);
          tetra->SetInputData(surface);
          tetra->SetMesher(mesher.c_str());
          tetra->SetUniformSizing(uniform);
          tetra->SetHxtOptimization(row.Optimize);
          tetra->SetTargetNumberOfTets(static_cast<vtkIdType>(target));
          const auto start = Clock::now();
          tetra->Update();
          times.push_back(MillisecondsSince(start));
          if (!messages.Errors.empty())
            throw translucency::Error(mesher + ": " + messages.Last());
          last = tetra->GetOutput();
        }
        std::vector<double> points;
        std::vector<int> tets;
        GridToCoreArrays(last, points, tets);
        const translucency::TetQualityStats q = translucency::ComputeTetQuality(points, tets, 1.414);
        const double below5 = 100.0 * static_cast<double>(q.TetsBelow5Degrees) / q.NumberOfTets;
        translucency::TetMesh topology;
        topology.SetGeometry(points, tets);
        const std::size_t boundaryPoints = topology.GetBoundaryPoints().size();
        const double ms = Median(times);
        std::ostringstream hist;
        json histogram = json::array();
        for (std::size_t count : q.MinDihedralHistogram)
        {
          const double percent = 100.0 * static_cast<double>(count) / q.NumberOfTets;
          hist << std::setprecision(percent < 10 ? 1 : 2) << std::fixed << percent << " ";
          histogram.push_back(percent);
        }
        std::cout << std::fixed << std::setprecision(2) << "  " << std::setw(6)
                  << static_cast<long>(target) << " " << std::setw(9) << label << "  "
                  << std::setw(7) << (uniform ? "uniform" : "graded") << " " << std::setw(10)
                  << q.NumberOfTets << " " << std::setw(10) << std::setprecision(0) << ms << " "
                  << std::setw(9) << std::setprecision(3) << q.NumberOfTets / ms / 1000.0 << " "
                  << std::setw(8) << std::setprecision(2) << q.MinDihedral << " " << std::setw(9)
                  << std::setprecision(3) << below5 << " " << std::setw(8) << std::setprecision(2)
                  << q.MaxRadiusEdge << " " << std::setw(9) << std::setprecision(3)
                  << q.MeanRadiusEdge << " " << std::setw(9) << std::setprecision(3)
                  << 100.0 * q.FractionAboveRadiusEdgeBound << " " << std::setw(8)
                  << q.EdgeLengthCV << " " << std::setw(13) << boundaryPoints << "  " << hist.str()
                  << "\n"
                  << std::defaultfloat;
        results.push_back({ { "target_tets", target }, { "mesher", label },
          { "uniform_sizing", uniform }, { "tets", q.NumberOfTets }, { "time_ms_median", ms },
          { "tets_per_second", q.NumberOfTets / ms * 1000.0 },
          { "speedup_vs_tetgen_graded_per_tet", 1.0 },
          { "min_dihedral_deg", q.MinDihedral }, { "max_dihedral_deg", q.MaxDihedral },
          { "percent_min_dihedral_below_5", below5 }, { "boundary_points", boundaryPoints },
          { "min_dihedral_histogram_percent", histogram },
          { "max_radius_edge", q.MaxRadiusEdge }, { "mean_radius_edge", q.MeanRadiusEdge },
          { "percent_radius_edge_above_1.414", 100.0 * q.FractionAboveRadiusEdgeBound },
          { "edge_length_cv", q.EdgeLengthCV }, { "mean_edge_mm", q.MeanEdgeLength } });
      }
    }
  }
  // Per-tet speed of each row against TetGen (graded) at the same target, same run.
  for (json& row : results)
  {
    for (const json& base : results)
    {
      if (base["target_tets"] == row["target_tets"] && base["mesher"] == "tetgen" &&
        base["uniform_sizing"] == false)
      {
        row["speedup_vs_tetgen_graded_per_tet"] =
          row["tets_per_second"].get<double>() / base["tets_per_second"].get<double>();
      }
    }
  }
  std::cout << "\nper-tet speed vs TetGen graded, same target, same run:";
  for (const json& row : results)
    std::cout << " " << row["mesher"].get<std::string>() << "/"
              << (row["uniform_sizing"].get<bool>() ? "uniform" : "graded") << "@"
              << row["target_tets"].get<double>() << " " << std::setprecision(3)
              << row["speedup_vs_tetgen_graded_per_tet"].get<double>() << "x;";
  std::cout << "\n";
  if (!o.JsonPath.empty() && !WriteText(o.JsonPath, results.dump(2) + "\n", error))
    throw translucency::Error(error);
  return 0;
}

} // namespace translucency_app
