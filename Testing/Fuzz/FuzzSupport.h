/**
 * @file FuzzSupport.h
 * @brief Shared pieces of the libFuzzer targets: the readers and loaders take
 * file names, so each input is written to a file in a private scratch
 * directory first; a small tetrahedral grid for the filters the loaders
 * configure.
 */
#pragma once

#include <vtkNew.h>
#include <vtkObject.h>
#include <vtkPoints.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <unistd.h>

namespace translucency_fuzz
{

/// The scratch directory of this process (created once; removed at exit).
inline const std::filesystem::path& ScratchDirectory()
{
  static const std::filesystem::path dir = []
  {
    std::filesystem::path d = std::filesystem::temp_directory_path() /
      ("translucency-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    // The readers report bad input with vtkErrorMacro: expected, and too
    // loud to print for every input.
    vtkObject::GlobalWarningDisplayOff();
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(std::filesystem::temp_directory_path() /
          ("translucency-fuzz-" + std::to_string(::getpid())),
        ec);
    });
    return d;
  }();
  return dir;
}

/// Write `size` bytes to `name` in the scratch directory; return its path.
inline std::string WriteInput(const std::string& name, const uint8_t* data, size_t size)
{
  const std::filesystem::path path = ScratchDirectory() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path.string();
}

/// Count one input's outcome ("clean error", "success" or "skipped": an
/// input the target does not run, e.g. fuzzMeshIO's without an extension
/// line) for a long run (scripts/fuzz_long.py, `make fuzz-long`): with
/// TRANSLUCENCY_FUZZ_TALLY=FILE the counts are added to FILE at exit
/// ("<outcome>: <count>" lines, and "<group> <outcome>: <count>" when a
/// group is given, e.g. the mesh format).
inline void Tally(const std::string& outcome, const std::string& group = std::string())
{
  static const char* file = std::getenv("TRANSLUCENCY_FUZZ_TALLY");
  if (!file)
  {
    return;
  }
  static std::map<std::string, long> counts;
  static const bool registered = []
  {
    std::atexit([] {
      if (FILE* out = std::fopen(std::getenv("TRANSLUCENCY_FUZZ_TALLY"), "a"))
      {
        for (const auto& [key, count] : counts)
        {
          std::fprintf(out, "%s: %ld\n", key.c_str(), count);
        }
        std::fclose(out);
      }
    });
    return true;
  }();
  (void)registered;
  ++counts[outcome];
  if (!group.empty())
  {
    ++counts[group + " " + outcome];
  }
}

/// Abort (a libFuzzer finding) when `condition` is false.
inline void Check(bool condition, const char* what)
{
  if (!condition)
  {
    std::fprintf(stderr, "fuzz check failed: %s\n", what);
    std::abort();
  }
}

/// A 2 x 2 x 2 block of unit cubes (mm), six tetrahedra each: 27 points, 48
/// tets, positively oriented.
inline vtkSmartPointer<vtkUnstructuredGrid> SmallTetGrid()
{
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i)
        points->InsertNextPoint(i, j, k);
  auto id = [](int i, int j, int k) { return static_cast<vtkIdType>(i + 3 * j + 9 * k); };
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->SetPoints(points);
  grid->Allocate(48);
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i)
      {
        // Kuhn triangulation of the cube along its main diagonal 0 -> 6.
        const vtkIdType c[8] = { id(i, j, k), id(i + 1, j, k), id(i + 1, j + 1, k),
          id(i, j + 1, k), id(i, j, k + 1), id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1),
          id(i, j + 1, k + 1) };
        const int tets[6][4] = { { 0, 1, 2, 6 }, { 0, 2, 3, 6 }, { 0, 3, 7, 6 },
          { 0, 7, 4, 6 }, { 0, 4, 5, 6 }, { 0, 5, 1, 6 } };
        for (const auto& t : tets)
        {
          const vtkIdType cell[4] = { c[t[0]], c[t[1]], c[t[2]], c[t[3]] };
          grid->InsertNextCell(VTK_TETRA, 4, cell);
        }
      }
  return grid;
}

} // namespace translucency_fuzz
