// `translucency acquire`: inverse diffusion (Polygrid, Sec. 4) from
// measurement files, or from synthetic measurements of a known volume.
#include "MeshIO.h"
#include "Options.h"
#include "Pictures.h"
#include "Provenance.h"
#include "PipelineRender.h"

#include "DiffusionForwardModel.h"
#include "Error.h"
#include "InputFiles.h"
#include "InverseDiffusion.h"
#include "TetMesh.h"
#include "vtkInverseDiffusion.h"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCommand.h>
#include <vtkDataArray.h>
#include <vtkDirectory.h>
#include <vtkDoubleArray.h>
#include <vtkImageData.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkProbeFilter.h>
#include <vtkTable.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLImageDataReader.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include "vtk_nlohmannjson.h"
#include VTK_NLOHMANN_JSON(json.hpp)

#include <algorithm>
#include <filesystem>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <random>
#include <sstream>
#include <thread>
#include <ctime>

namespace translucency_app
{

namespace
{
using json = nlohmann::json;

std::string Indexed(const char* base, size_t k)
{
  return std::string(base) + "_" + std::to_string(k);
}

/// A new 3-component double array (caller owns the reference).
vtkDataArray* NewTriple(const std::string& name, const std::vector<double>& values)
{
  vtkDoubleArray* a = vtkDoubleArray::New();
  a->SetName(name.c_str());
  a->SetNumberOfComponents(3);
  a->SetNumberOfTuples(static_cast<vtkIdType>(values.size() / 3));
  std::copy(values.begin(), values.end(), a->GetPointer(0));
  return a;
}

vtkSmartPointer<vtkUnstructuredGrid> ReadGrid(const std::string& path)
{
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  translucency::CheckInputFile(path, "mesh file"); // before any read: not a FIFO
  if (Extension(path) != "vtu" || !reader->CanReadFile(path.c_str()))
  {
    throw translucency::Error(path + ": not a readable .vtu file");
  }
  CheckVtkXmlFile(path);
  reader->SetFileName(path.c_str());
  reader->Update();
  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->ShallowCopy(reader->GetOutput());
  if (grid->GetNumberOfPoints() == 0)
  {
    throw translucency::Error(path + ": no points");
  }
  return grid;
}

/// Copy the measurement arrays of --patterns onto `sample`.
void AttachPatterns(vtkUnstructuredGrid* sample, const std::string& patterns)
{
  vtkNew<vtkDirectory> dir;
  if (dir->Open(patterns.c_str()))
  {
    std::vector<std::string> files;
    for (vtkIdType k = 0; k < dir->GetNumberOfFiles(); ++k)
    {
      const std::string name = dir->GetFile(k);
      if (Extension(name) == "vtu")
      {
        files.push_back(patterns + "/" + name);
      }
    }
    std::sort(files.begin(), files.end());
    if (files.empty())
    {
      throw translucency::Error(patterns + ": no .vtu file in the directory");
    }
    for (size_t k = 0; k < files.size(); ++k)
    {
      auto grid = ReadGrid(files[k]);
      if (grid->GetNumberOfPoints() != sample->GetNumberOfPoints())
      {
        throw translucency::Error(files[k] + ": " + std::to_string(grid->GetNumberOfPoints()) +
          " points but the sample has " + std::to_string(sample->GetNumberOfPoints()));
      }
      for (const char* name : { "Irradiance", "Radiance", "ObservedMask" })
      {
        vtkDataArray* a = grid->GetPointData()->GetArray(name);
        if (!a)
        {
          if (std::string(name) == "ObservedMask")
            continue;
          throw translucency::Error(files[k] + ": no '" + name + "' point array");
        }
        vtkSmartPointer<vtkDataArray> copy;
        copy.TakeReference(a->NewInstance());
        copy->DeepCopy(a);
        copy->SetName(Indexed(name, k).c_str());
        sample->GetPointData()->AddArray(copy);
      }
    }
    return;
  }
  auto grid = ReadGrid(patterns);
  if (grid->GetNumberOfPoints() != sample->GetNumberOfPoints())
  {
    throw translucency::Error(patterns + ": " + std::to_string(grid->GetNumberOfPoints()) +
      " points but the sample has " + std::to_string(sample->GetNumberOfPoints()));
  }
  vtkPointData* pd = grid->GetPointData();
  int copied = 0;
  for (int a = 0; a < pd->GetNumberOfArrays(); ++a)
  {
    const char* name = pd->GetArrayName(a);
    const std::string n = name ? name : "";
    if (n.rfind("Irradiance_", 0) == 0 || n.rfind("Radiance_", 0) == 0 ||
      n.rfind("ObservedMask", 0) == 0)
    {
      sample->GetPointData()->AddArray(pd->GetArray(a));
      ++copied;
    }
  }
  if (copied == 0)
  {
    throw translucency::Error(patterns + ": no Irradiance_<k> / Radiance_<k> point arrays");
  }
}

/// Every measurement array of `sample` (Irradiance_<k>, Radiance_<k>) must
/// be finite: a -inf or NaN measurement made the fit meaningless while the
/// run exited 0. Throws translucency::Error naming the array, point and value.
void CheckMeasurementsFinite(vtkUnstructuredGrid* sample, const std::string& patterns)
{
  vtkPointData* pd = sample->GetPointData();
  for (int a = 0; a < pd->GetNumberOfArrays(); ++a)
  {
    vtkDataArray* array = pd->GetArray(a);
    const std::string name = array && array->GetName() ? array->GetName() : "";
    if (name.rfind("Irradiance_", 0) != 0 && name.rfind("Radiance_", 0) != 0)
      continue;
    for (vtkIdType i = 0; i < array->GetNumberOfTuples(); ++i)
      for (int c = 0; c < array->GetNumberOfComponents(); ++c)
      {
        const double value = array->GetComponent(i, c);
        if (!std::isfinite(value))
        {
          std::ostringstream os;
          os << "--patterns " << patterns << ": measurement '" << name << "' holds " << value
             << " at point " << i << " (component " << c
             << "): every measurement must be a finite number";
          throw translucency::Error(os.str());
        }
      }
  }
}

/// The synthetic problem: block mesh, truth per voxel, measurements.
struct Synthetic
{
  int N[3] = { 0, 0, 0 };
  double Origin[3], Size[3];
  std::vector<double> Kappa, Mu; ///< truth, 3 per voxel
  std::vector<std::vector<double>> Irradiance, Radiance;
  std::vector<std::vector<unsigned char>> Observed;
  translucency::AcquisitionSetup Setup = translucency::AcquisitionSetup::Back;
};

vtkSmartPointer<vtkDataSet> ReadTruth(const std::string& path)
{
  const std::string ext = Extension(path);
  if (ext == "vti")
  {
    vtkNew<vtkXMLImageDataReader> reader;
    translucency::CheckInputFile(path, "--synthetic-truth file"); // before any read
    if (!reader->CanReadFile(path.c_str()))
      throw translucency::Error(path + ": not a readable .vti file");
    CheckVtkXmlFile(path);
    reader->SetFileName(path.c_str());
    reader->Update();
    auto out = vtkSmartPointer<vtkImageData>::New();
    out->ShallowCopy(reader->GetOutput());
    return out;
  }
  if (ext == "vtu")
  {
    return ReadGrid(path);
  }
  throw translucency::Error(path + ": the synthetic truth must be .vti or .vtu");
}

vtkSmartPointer<vtkUnstructuredGrid> BuildSynthetic(const std::string& truthPath, const int grid[3],
  int rows, int cols, double noise, unsigned seed, Synthetic& s)
{
  vtkSmartPointer<vtkDataSet> truth = ReadTruth(truthPath);
  double b[6];
  truth->GetBounds(b);
  for (int d = 0; d < 3; ++d)
  {
    s.N[d] = grid[d];
    s.Origin[d] = b[2 * d];
    s.Size[d] = b[2 * d + 1] - b[2 * d];
    if (!(s.Size[d] > 0.0))
      throw translucency::Error(truthPath + ": the truth volume is flat (bounds " +
        std::to_string(b[2 * d]) + " .. " + std::to_string(b[2 * d + 1]) + ")");
  }
  std::vector<double> points;
  std::vector<int> tets, element;
  translucency::BuildGridBlock(grid[0], grid[1], grid[2], s.Origin, s.Size, points, tets, element);
  const int numVoxels = grid[0] * grid[1] * grid[2];

  // Voxel centres, probed in the truth (cell or point data).
  vtkNew<vtkPolyData> centres;
  vtkNew<vtkPoints> centrePoints;
  for (int k = 0; k < grid[2]; ++k)
    for (int j = 0; j < grid[1]; ++j)
      for (int i = 0; i < grid[0]; ++i)
        centrePoints->InsertNextPoint(s.Origin[0] + s.Size[0] * (i + 0.5) / grid[0],
          s.Origin[1] + s.Size[1] * (j + 0.5) / grid[1], s.Origin[2] + s.Size[2] * (k + 0.5) / grid[2]);
  centres->SetPoints(centrePoints);
  vtkNew<vtkProbeFilter> probe;
  probe->SetInputData(centres);
  probe->SetSourceData(truth);
  probe->Update();
  vtkPointData* sampled = probe->GetOutput()->GetPointData();
  vtkDataArray* mu = sampled->GetArray("AbsorptionCoefficient");
  vtkDataArray* sigma = sampled->GetArray("ReducedScatteringCoefficient");
  vtkDataArray* eta = sampled->GetArray("RefractiveIndex");
  if (!mu || !sigma || mu->GetNumberOfComponents() != 3 || sigma->GetNumberOfComponents() != 3)
    throw translucency::Error(truthPath + ": needs AbsorptionCoefficient and "
                                          "ReducedScatteringCoefficient arrays with 3 components");
  s.Kappa.resize(3 * numVoxels);
  s.Mu.resize(3 * numVoxels);
  std::vector<double> voxelEta(numVoxels, 1.3);
  for (int v = 0; v < numVoxels; ++v)
  {
    for (int c = 0; c < 3; ++c)
    {
      const double m = mu->GetComponent(v, c), sg = sigma->GetComponent(v, c);
      if (!(std::isfinite(m) && m > 0.0 && std::isfinite(sg) && sg >= 0.0))
      {
        std::ostringstream os;
        os << truthPath << ": at voxel " << v << " (centre " << centrePoints->GetPoint(v)[0] << ", "
           << centrePoints->GetPoint(v)[1] << ", " << centrePoints->GetPoint(v)[2]
           << "), channel " << c << ": mu_a = " << m << ", sigma_s' = " << sg
           << " (need mu_a > 0, sigma_s' >= 0)";
        throw translucency::Error(os.str());
      }
      s.Mu[3 * v + c] = m;
      s.Kappa[3 * v + c] = 1.0 / (3.0 * (m + sg));
    }
    if (eta)
      voxelEta[v] = eta->GetComponent(v, 0);
  }

  // The tet mesh.
  auto mesh = vtkSmartPointer<vtkUnstructuredGrid>::New();
  vtkNew<vtkPoints> pts;
  pts->SetDataTypeToDouble();
  pts->SetNumberOfPoints(static_cast<vtkIdType>(points.size() / 3));
  for (size_t i = 0; i < points.size() / 3; ++i)
    pts->SetPoint(static_cast<vtkIdType>(i), &points[3 * i]);
  mesh->SetPoints(pts);
  vtkNew<vtkCellArray> cells;
  for (size_t t = 0; t < tets.size() / 4; ++t)
  {
    const vtkIdType ids[4] = { tets[4 * t], tets[4 * t + 1], tets[4 * t + 2], tets[4 * t + 3] };
    cells->InsertNextCell(4, ids);
  }
  mesh->SetCells(VTK_TETRA, cells);
  vtkNew<vtkIntArray> voxelIds;
  voxelIds->SetName("VoxelId");
  vtkNew<vtkDoubleArray> tetEta;
  tetEta->SetName("RefractiveIndex");
  for (int e : element)
  {
    voxelIds->InsertNextValue(e);
    tetEta->InsertNextValue(voxelEta[e]);
  }
  mesh->GetCellData()->AddArray(voxelIds);
  mesh->GetCellData()->AddArray(tetEta);

  // Measurements (paper Sec. 4.1 setups), from the forward model.
  translucency::TetMesh core;
  core.SetGeometry(points, tets);
  std::vector<double> etaPerTet(element.size());
  for (size_t t = 0; t < element.size(); ++t)
    etaPerTet[t] = voxelEta[element[t]];
  translucency::DiffusionForwardModel model(core, element, numVoxels, etaPerTet);
  translucency::MakeBlockPatterns(points, rows, cols, s.Setup, 1.0, s.Irradiance, s.Observed);
  s.Radiance = translucency::InverseDiffusion::PredictRadiance(model, s.Kappa, s.Mu, s.Irradiance);
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (size_t m = 0; m < s.Radiance.size(); ++m)
  {
    for (int c = 0; c < 3; ++c)
    {
      double peak = 0.0;
      for (size_t i = 0; i < s.Observed[m].size(); ++i)
        if (s.Observed[m][i])
          peak = std::max(peak, std::abs(s.Radiance[m][3 * i + c]));
      for (size_t i = 0; i < s.Observed[m].size(); ++i)
        if (s.Observed[m][i] && noise > 0.0)
          s.Radiance[m][3 * i + c] += noise * peak * gauss(rng);
    }
  }
  for (size_t m = 0; m < s.Irradiance.size(); ++m)
  {
    vtkSmartPointer<vtkDataArray> q, l;
    q.TakeReference(NewTriple(Indexed("Irradiance", m), s.Irradiance[m]));
    l.TakeReference(NewTriple(Indexed("Radiance", m), s.Radiance[m]));
    vtkNew<vtkUnsignedCharArray> obs;
    obs->SetName(Indexed("ObservedMask", m).c_str());
    for (unsigned char o : s.Observed[m])
      obs->InsertNextValue(o);
    mesh->GetPointData()->AddArray(q);
    mesh->GetPointData()->AddArray(l);
    mesh->GetPointData()->AddArray(obs);
  }
  return mesh;
}

/// Viridis (perceptually uniform, Pictures.h) at t in [0, 1], as 8-bit RGB.
void Ramp(double t, unsigned char rgb[3])
{
  double c[3];
  SampleColourMap(ColourMap::Viridis, t, c);
  for (int k = 0; k < 3; ++k)
    rgb[k] = static_cast<unsigned char>(std::lround(255.0 * c[k]));
}

/// A picture made of tiles of scalar maps (no rendering: written directly).
struct Mosaic
{
  int Width, Height;
  std::vector<unsigned char> Pixels; ///< RGB, row 0 at the top
  Mosaic(int w, int h)
    : Width(w)
    , Height(h)
    , Pixels(3 * static_cast<size_t>(w) * h, 255)
  {
  }
  /// Draw an nx x ny map (value(i, j), NaN = not observed: grey) scaled by
  /// `scale` pixels, top-left corner (x0, y0); j grows upwards.
  template <class F>
  void Tile(int x0, int y0, int nx, int ny, int scale, double lo, double hi, F value)
  {
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
      {
        const double v = value(i, j);
        unsigned char rgb[3] = { 128, 128, 128 };
        if (std::isfinite(v))
          Ramp(hi > lo ? (v - lo) / (hi - lo) : 0.5, rgb);
        for (int dy = 0; dy < scale; ++dy)
          for (int dx = 0; dx < scale; ++dx)
          {
            const int x = x0 + i * scale + dx, y = y0 + (ny - 1 - j) * scale + dy;
            if (x < 0 || y < 0 || x >= Width || y >= Height)
              continue;
            unsigned char* p = &Pixels[3 * (static_cast<size_t>(y) * Width + x)];
            p[0] = rgb[0];
            p[1] = rgb[1];
            p[2] = rgb[2];
          }
      }
  }
  bool Write(const std::string& path, std::string& error) const
  {
    vtkNew<vtkImageData> image;
    image->SetDimensions(Width, Height, 1);
    vtkNew<vtkUnsignedCharArray> rgb;
    rgb->SetNumberOfComponents(3);
    rgb->SetNumberOfTuples(static_cast<vtkIdType>(Width) * Height);
    for (int y = 0; y < Height; ++y) // VTK images start at the bottom row
      std::copy(&Pixels[3 * static_cast<size_t>(Height - 1 - y) * Width],
        &Pixels[3 * static_cast<size_t>(Height - y) * Width],
        rgb->GetPointer(3 * static_cast<vtkIdType>(y) * Width));
    image->GetPointData()->SetScalars(rgb);
    TemporaryFile tmp(path); // unique, exclusive, renamed over `path` (OutputFiles.h)
    if (tmp.Path().empty())
    {
      error = tmp.Error();
      return false;
    }
    vtkNew<vtkPNGWriter> writer;
    writer->SetFileName(tmp.Path().c_str());
    writer->SetInputData(image);
    writer->Write();
    if (writer->GetErrorCode() != 0)
    {
      error = "cannot write " + path;
      return false;
    }
    return tmp.Commit(error);
  }
};

int TileScale(int n)
{
  return std::max(1, std::min(16, 160 / std::max(1, n)));
}

/// Measured | fitted radiance (G channel) on the observed face, per pattern.
bool WriteRadianceMosaic(const Synthetic& s, const std::vector<std::vector<double>>& fitted,
  int cols, const std::string& path, std::string& error)
{
  const int px = s.N[0] + 1, py = s.N[1] + 1;
  const int k = s.Setup == translucency::AcquisitionSetup::Back ? s.N[2] : 0;
  const int scale = TileScale(std::max(px, py));
  const int tileW = px * scale, tileH = py * scale, gap = 6;
  const int numPatterns = static_cast<int>(s.Radiance.size());
  const int rows = (numPatterns + cols - 1) / cols;
  const int tilesHeight = rows * (tileH + gap) + gap;
  Mosaic mosaic(std::max(cols * (2 * tileW + 3 * gap), 320), tilesHeight + ColourBarHeight() + gap);
  for (int m = 0; m < numPatterns; ++m)
  {
    double hi = 0.0;
    for (size_t i = 0; i < s.Observed[m].size(); ++i)
      if (s.Observed[m][i])
        hi = std::max(hi, s.Radiance[m][3 * i + 1]);
    const int x0 = (m % cols) * (2 * tileW + 3 * gap) + gap, y0 = (m / cols) * (tileH + gap) + gap;
    for (int which = 0; which < 2; ++which)
    {
      const std::vector<double>& l = which == 0 ? s.Radiance[m] : fitted[m];
      mosaic.Tile(x0 + which * (tileW + gap), y0, px, py, scale, 0.0, 1.0, [&](int i, int j) {
        const size_t id = i + static_cast<size_t>(px) * (j + static_cast<size_t>(py) * k);
        return s.Observed[m][id] && hi > 0 ? l[3 * id + 1] / hi : std::nan("");
      });
    }
  }
  DrawColourBar({ mosaic.Width, mosaic.Height, &mosaic.Pixels }, gap, tilesHeight,
    std::min(mosaic.Width - 2 * gap, 400), ColourMap::Viridis, 0.0, 1.0,
    "radiance G / the pattern's measured peak (measured | fitted)", "1");
  return mosaic.Write(path, error);
}

/// Layers under the observed face, nearest first (several depths).
std::vector<int> SliceLayers(const Synthetic& s)
{
  std::vector<int> layers;
  const int nz = s.N[2];
  const int step = std::max(1, nz / 4);
  for (int d = 0; d < nz && layers.size() < 4; d += step)
    layers.push_back(s.Setup == translucency::AcquisitionSetup::Back ? nz - 1 - d : d);
  return layers;
}

/// Recovered | true kappa and recovered | true mu_a (G) on layers at several
/// depths below the observed face (paper Fig. 14 style), one row per depth.
bool WriteSliceMosaic(const Synthetic& s, const std::vector<double>& kappa,
  const std::vector<double>& mu, const std::string& path, std::string& error)
{
  const int nx = s.N[0], ny = s.N[1];
  const int scale = TileScale(std::max(nx, ny));
  const int tileW = nx * scale, tileH = ny * scale, gap = 6;
  const std::vector<int> layers = SliceLayers(s);
  const int tilesHeight = static_cast<int>(layers.size()) * (tileH + gap) + gap;
  const int halfWidth = std::max(2 * (tileW + gap), 240);
  Mosaic mosaic(2 * halfWidth + 2 * gap, tilesHeight + ColourBarHeight() + gap);
  double range[2][2];
  for (int q = 0; q < 2; ++q)
  {
    const std::vector<double>& a = q == 0 ? kappa : mu;
    const std::vector<double>& t = q == 0 ? s.Kappa : s.Mu;
    range[q][0] = 1e300;
    range[q][1] = -1e300;
    for (size_t v = 0; v < a.size() / 3; ++v)
      for (double x : { a[3 * v + 1], t[3 * v + 1] })
      {
        range[q][0] = std::min(range[q][0], x);
        range[q][1] = std::max(range[q][1], x);
      }
  }
  for (size_t r = 0; r < layers.size(); ++r)
  {
    const int k = layers[r];
    for (int col = 0; col < 4; ++col)
    {
      const int q = col / 2;
      const std::vector<double>& a =
        col == 0 ? kappa : col == 1 ? s.Kappa : col == 2 ? mu : s.Mu;
      const int x0 = (col >= 2 ? halfWidth + gap : 0) + (col % 2) * (tileW + gap) + gap;
      const int y0 = static_cast<int>(r) * (tileH + gap) + gap;
      mosaic.Tile(x0, y0, nx, ny, scale, range[q][0], range[q][1],
        [&](int i, int j) { return a[3 * (i + static_cast<size_t>(nx) * (j + static_cast<size_t>(ny) * k)) + 1]; });
    }
  }
  const int barWidth = halfWidth - 3 * gap;
  DrawColourBar({ mosaic.Width, mosaic.Height, &mosaic.Pixels }, gap, tilesHeight, barWidth,
    ColourMap::Viridis, range[0][0], range[0][1], "kappa G (recovered | true)", "mm");
  DrawColourBar({ mosaic.Width, mosaic.Height, &mosaic.Pixels }, halfWidth + 2 * gap, tilesHeight,
    barWidth, ColourMap::Viridis, range[1][0], range[1][1], "mu_a G (recovered | true)", "1/mm");
  return mosaic.Write(path, error);
}

double Correlation(const std::vector<double>& x, const std::vector<double>& y)
{
  // Undefined (NaN) when either side is constant.
  if (x.empty() || *std::min_element(x.begin(), x.end()) == *std::max_element(x.begin(), x.end()) ||
    *std::min_element(y.begin(), y.end()) == *std::max_element(y.begin(), y.end()))
    return std::nan("");
  const double n = static_cast<double>(x.size());
  double mx = 0, my = 0, sxy = 0, sxx = 0, syy = 0;
  for (size_t i = 0; i < x.size(); ++i)
  {
    mx += x[i] / n;
    my += y[i] / n;
  }
  for (size_t i = 0; i < x.size(); ++i)
  {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
    syy += (y[i] - my) * (y[i] - my);
  }
  return sxx > 0 && syy > 0 ? sxy / std::sqrt(sxx * syy) : std::nan("");
}

int ParseCount(const std::string& text, const std::string& what)
{
  char* end = nullptr;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (!end || *end != '\0' || v < 1 || v > 100000)
    throw UsageError(what + ": '" + text + "' is not a positive integer");
  return static_cast<int>(v);
}

/// "AxBxC" -> numbers (2 or 3 of them).
std::vector<int> ParseDims(const std::string& text, const std::string& what, size_t count)
{
  std::vector<int> dims;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, 'x'))
    dims.push_back(ParseCount(item, what));
  if (dims.size() != count)
    throw UsageError(what + ": '" + text + "' should be " + (count == 3 ? "NXxNYxNZ" : "RxC"));
  return dims;
}
struct AcquireOptions
{
  std::string SamplePath, PatternsArg, OutputPrefix, JsonPath, TruthPath, GridArg, ElementArray;
  std::string HomogeneousFit = "gauss-newton";
  std::string LineSearchStart = "gauss-newton";
  std::string SetupName = "back";
  double Lambda = 1e-5, Threshold = 1e-4, Noise = 0.0;
  int MaxIter = 100;
  unsigned Seed = 1;
  bool NoPng = false;
  std::vector<double> InitialMu = { 0.01 }, InitialSigma = { 1.0 };
  const CLI::App* App = nullptr; ///< for the provenance of the JSON
};

/// Acquire: the checks of the options alone (before any work); the initial
/// coefficients as 3 values each.
void CheckAcquireOptions(
  const AcquireOptions& o, std::vector<double>& initialMu, std::vector<double>& initialSigma)
{
  initialMu = o.InitialMu;
  initialSigma = o.InitialSigma;
  if (initialMu.size() == 1)
    initialMu.assign(3, initialMu[0]);
  if (initialSigma.size() == 1)
    initialSigma.assign(3, initialSigma[0]);
  if (initialMu.size() != 3 || initialSigma.size() != 3)
    throw UsageError("acquire: --initial-mua and --initial-sigmas take 1 or 3 values");
  const bool synthetic = !o.TruthPath.empty();
  if (o.PatternsArg.empty())
    throw UsageError("acquire: --patterns is required");
  if (!synthetic && o.SamplePath.empty())
    throw UsageError("acquire: --sample FILE (or --synthetic-truth FILE) is required");
  if (synthetic && o.GridArg.empty())
    throw UsageError("acquire: --synthetic-truth needs --grid NXxNYxNZ");
}

/// Acquire, before any work: no output may be an input or another output,
/// and a second run into the same prefix is refused (OutputFiles.h). `plan`
/// holds the locks: the caller keeps it for the whole run.
void PlanAcquireOutputs(const AcquireOptions& o, OutputPlan& plan)
{
  const bool synthetic = !o.TruthPath.empty(), png = !o.NoPng;
  const std::string& outputPrefix = o.OutputPrefix;
  plan.Input(o.SamplePath, "--sample");
  plan.Input(o.TruthPath, "--synthetic-truth");
  if (!synthetic && !std::filesystem::is_directory(o.PatternsArg))
    plan.Input(o.PatternsArg, "--patterns");
  plan.Output(outputPrefix + ".vtu", "--output");
  if (synthetic)
  {
    plan.Output(outputPrefix + "_measurements.vtu", "--output", false);
    if (png)
    {
      plan.Output(outputPrefix + "_radiance.png", "--output", false);
      plan.Output(outputPrefix + "_slices.png", "--output", false);
    }
  }
  if (png)
    plan.Output(outputPrefix + "_objective.png", "--output", false);
  plan.Output(o.JsonPath, "--json", false);
  plan.Check();
}

/// Acquire: what the fit will cost, estimated before it runs. The old figure
/// (4e-6 s per point x pattern x iteration, measured on two small grids) said
/// 5.1 s for a fit of 39 s of CPU: a factorisation grows faster than the
/// points, and each iteration is several forward passes. Now: the passes the
/// fit makes (counted by the same rules as InverseDiffusion's optimiser) times
/// the cost of one factorisation and one blocked solve, measured here on the
/// same grid (or a smaller one of the same shape, scaled up).
struct FitEstimate
{
  double Points = 0.0;         ///< of the problem
  int Patterns = 0;
  int Iterations = 0;          ///< heterogeneous iterations per channel (--max-iter: all run)
  double ForwardPasses = 0.0;  ///< all channels: factorisation + M-column solve
  double AdjointPasses = 0.0;  ///< all channels: M-column solve
  double TangentPasses = 0.0;  ///< all channels: M-column solve (2M in the homogeneous fit)
  double SolveColumns = 0.0;   ///< all channels: blocked solves in units of M columns
  double CalibrationPoints = 0.0;
  double FactorSeconds = 0.0;  ///< CPU seconds of one numeric factorisation at Points
  double SolveSeconds = 0.0;   ///< CPU seconds of one M-column solve at Points
  double CpuSeconds = 0.0;     ///< the fit, summed over the 3 channels
  bool Scaled = false;         ///< calibrated on fewer points and scaled up
};

// Per channel, counted on 10x10x3, 16x16x4 and 32x32x8 grids with 2x2
// patterns and --threshold 0 (every iteration runs): the Levenberg-Marquardt
// homogeneous fit stops after 4-6 iterations (one trial forward pass and one
// tangent solve each); each heterogeneous iteration makes one adjoint pass,
// one tangent pass (the Gauss-Newton start of the line search) and 6 forward
// passes (the golden-section search from that start; 6-9, mostly 7, from
// the previous step). The paper's CG for the homogeneous pair stops after
// 5-9 iterations of 6-11 forward passes (mostly 7-8) and one adjoint pass.
constexpr int EstimatedHomogeneousIterations = 6;
constexpr int EstimatedCgHomogeneousIterations = 7;
constexpr int EstimatedCgHomogeneousPasses = 8;
constexpr int EstimatedGaussNewtonStartPasses = 6;
constexpr int EstimatedPreviousStartPasses = 7;
// Calibration above this many points is done on a smaller grid of the same
// shape; the factorisation's time then scales as points^1.5 and a solve's as
// points^(4/3) (nested dissection on a 3D grid: fill ~ n^(4/3), work grows
// faster than n^1.5: so a scaled estimate is a lower bound).
constexpr double CalibrationPointLimit = 4000.0;

double ProcessCpuSeconds()
{
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// The passes of the fit (all three channels) if every iteration runs.
void CountEstimatedPasses(const AcquireOptions& o, FitEstimate& e)
{
  const double k = std::max(o.MaxIter, 0);
  const bool gaussNewtonStart = o.LineSearchStart == "gauss-newton", cg = o.HomogeneousFit == "cg";
  const double h = cg ? EstimatedCgHomogeneousIterations : EstimatedHomogeneousIterations;
  double forward = 1.0 +
    k * (gaussNewtonStart ? EstimatedGaussNewtonStartPasses : EstimatedPreviousStartPasses);
  double adjoint = k + 1.0, tangent = 0.0;
  if (cg)
  {
    forward += h * EstimatedCgHomogeneousPasses;
    adjoint += h + 1.0;
  }
  else
  {
    forward += h;
    tangent += h + 1.0;
  }
  if (gaussNewtonStart)
    tangent += k;
  e.Iterations = o.MaxIter;
  e.ForwardPasses = 3.0 * forward;
  e.AdjointPasses = 3.0 * adjoint;
  e.TangentPasses = 3.0 * tangent;
  // The homogeneous fit's tangent passes solve for two directions (2M columns).
  const double wideTangents = cg ? 0.0 : h + 1.0;
  e.SolveColumns = e.ForwardPasses + e.AdjointPasses + e.TangentPasses + 3.0 * wideTangents;
}

/// The estimate for a block of dims[0] x dims[1] x dims[2] voxels (the
/// synthetic grid, or a cube of the sample's number of points) and
/// `patterns` patterns: the passes, and the CPU time of a factorisation and
/// a blocked solve measured on that grid (at most CalibrationPointLimit
/// points: larger grids are calibrated on a smaller one of the same shape).
FitEstimate EstimateFit(const AcquireOptions& o, const double dims[3], int patterns)
{
  FitEstimate e;
  e.Points = (dims[0] + 1.0) * (dims[1] + 1.0) * (dims[2] + 1.0);
  e.Patterns = patterns;
  CountEstimatedPasses(o, e);
  const double shrink = std::min(1.0, std::cbrt(CalibrationPointLimit / e.Points));
  int n[3];
  for (int d = 0; d < 3; ++d)
    n[d] = std::max(1, static_cast<int>(std::lround(dims[d] * shrink)));
  std::vector<double> points;
  std::vector<int> tets, element;
  const double origin[3] = { 0.0, 0.0, 0.0 }, size[3] = { 1.0, 1.0, 1.0 };
  translucency::BuildGridBlock(n[0], n[1], n[2], origin, size, points, tets, element);
  translucency::TetMesh mesh;
  mesh.SetGeometry(points, tets);
  const int elements = n[0] * n[1] * n[2];
  translucency::DiffusionForwardModel model(
    mesh, element, elements, std::vector<double>(element.size(), 1.3));
  e.CalibrationPoints = static_cast<double>(model.GetNumberOfPoints());
  e.Scaled = e.CalibrationPoints < e.Points;
  // The fit's start: kappa = 1 / (3 (mu_a + sigma_s')) everywhere.
  const std::vector<double> mu(elements, 0.01), kappa(elements, 1.0 / (3.0 * 1.01));
  const Eigen::MatrixXd rhs = Eigen::MatrixXd::Ones(model.GetNumberOfPoints(), std::max(patterns, 1));
  Eigen::MatrixXd phi;
  // As in the fit: one BLAS thread per channel thread.
  const int blasThreads = translucency::DiffusionForwardModel::SetBlasThreads(1);
  translucency::DiffusionForwardModel::Factor factor;
  model.Factorize(kappa.data(), mu.data(), factor); // the symbolic analysis, kept by the fit
  const int repeats = 3;
  double start = ProcessCpuSeconds();
  for (int r = 0; r < repeats; ++r)
    model.Factorize(kappa.data(), mu.data(), factor);
  const double factorSeconds = (ProcessCpuSeconds() - start) / repeats;
  start = ProcessCpuSeconds();
  for (int r = 0; r < repeats; ++r)
    factor.Solve(rhs, phi);
  const double solveSeconds = (ProcessCpuSeconds() - start) / repeats;
  if (blasThreads > 0)
    translucency::DiffusionForwardModel::SetBlasThreads(blasThreads);
  const double ratio = e.Points / e.CalibrationPoints;
  e.FactorSeconds = factorSeconds * std::pow(ratio, 1.5);
  e.SolveSeconds = solveSeconds * std::pow(ratio, 4.0 / 3.0);
  e.CpuSeconds = e.ForwardPasses * e.FactorSeconds + e.SolveColumns * e.SolveSeconds;
  return e;
}

/// "6.75 ms", "40 s", "12 min", "3.2 h".
std::string FormatDuration(double seconds)
{
  if (seconds < 1.0)
    return translucency::FormatNumber(std::round(seconds * 1e5) / 100.0) + " ms";
  if (seconds < 120.0)
    return translucency::FormatNumber(std::round(seconds * 10.0) / 10.0) + " s";
  if (seconds < 7200.0)
    return translucency::FormatNumber(std::round(seconds / 60.0)) + " min";
  return translucency::FormatNumber(std::round(seconds / 360.0) / 10.0) + " h";
}

/// One line: the estimate and what it rests on.
std::string DescribeEstimate(const FitEstimate& e)
{
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  const double wall = e.CpuSeconds / std::min(3u, cores);
  std::ostringstream os;
  os << "about " << FormatDuration(e.CpuSeconds)
     << " of CPU (" << FormatDuration(wall) << " on " << std::min(3u, cores)
     << " idle cores) if all " << e.Iterations << " iterations run: "
     << translucency::FormatNumber(std::round(e.ForwardPasses)) << " forward passes ("
     << "factorisation " << FormatDuration(e.FactorSeconds) << " + " << e.Patterns
     << " solves " << FormatDuration(e.SolveSeconds) << " on " << translucency::FormatNumber(e.Points) << " points, measured"
     << (e.Scaled ? " on " + translucency::FormatNumber(e.CalibrationPoints) + " points and scaled"
                  : std::string(" here"))
     << "), " << translucency::FormatNumber(std::round(e.AdjointPasses + e.TangentPasses))
     << " adjoint and tangent solves";
  return os.str();
}

/// The estimate for the fit of `input` (after its patterns are attached):
/// the synthetic grid itself, or for a sample a cube of as many points.
FitEstimate EstimateInputFit(const AcquireOptions& o, vtkUnstructuredGrid* input, bool synthetic)
{
  int patterns = 0;
  while (input->GetPointData()->GetArray(Indexed("Irradiance", patterns).c_str()))
    ++patterns;
  double dims[3];
  if (synthetic)
  {
    const std::vector<int> grid = ParseDims(o.GridArg, "--grid", 3);
    for (int d = 0; d < 3; ++d)
      dims[d] = grid[d];
  }
  else
  {
    const double side = std::max(1.0, std::cbrt(static_cast<double>(input->GetNumberOfPoints())) - 1.0);
    dims[0] = dims[1] = dims[2] = side;
  }
  return EstimateFit(o, dims, patterns);
}

/// Acquire, report: the estimate next to what the fit did (passes counted by
/// the filter, CPU time of the process during the fit).
void ReportEstimate(const FitEstimate& e, double fitCpu, json& report)
{
  report["estimate"] = { { "iterations", e.Iterations }, { "forward_passes", e.ForwardPasses },
    { "adjoint_passes", e.AdjointPasses }, { "tangent_passes", e.TangentPasses },
    { "seconds_per_factorization", e.FactorSeconds }, { "seconds_per_solve", e.SolveSeconds },
    { "calibration_points", e.CalibrationPoints }, { "scaled", e.Scaled },
    { "cpu_seconds", e.CpuSeconds } };
  report["cpu_seconds_fit"] = fitCpu;
}

/// Acquire, synthetic mode: every pattern keeps its measured, forward and
/// adjoint fields (3 channels) at every point of the block: refuse a --grid
/// and --patterns that cannot fit, or whose fit would run for hours, before
/// building anything.
void CheckSyntheticBudget(const AcquireOptions& o, const std::vector<int>& grid,
  const std::vector<int>& rc)
{
  const std::string &gridArg = o.GridArg, &patternsArg = o.PatternsArg;
  const int maxIter = o.MaxIter;
  const double points = (grid[0] + 1.0) * (grid[1] + 1.0) * (grid[2] + 1.0);
  const double patterns = static_cast<double>(rc[0]) * rc[1];
  if (patterns > 4096)
  {
    // Each pattern is a forward and an adjoint solve per iteration.
    throw UsageError("acquire: --patterns " + patternsArg + " gives " +
      translucency::FormatNumber(patterns) +
      " patterns; at most 4096 are supported (each is a forward and an adjoint solve per "
      "iteration)");
  }
  const double bytes =
    translucency::EstimateGridBlockMemory(grid[0], grid[1], grid[2]) + patterns * points * 72.0;
  try
  {
    translucency::CheckMemory("acquire: --grid " + gridArg + " with --patterns " +
        patternsArg + " (" + translucency::FormatNumber(patterns) + " patterns)",
      bytes, translucency::GetDefaultMemoryLimit(), "use a coarser --grid or fewer --patterns");
  }
  catch (const translucency::Error& e)
  {
    throw UsageError(e.what());
  }
  // Work: every inverse iteration solves forward and adjoint problems for
  // every pattern on every point; the budget (1.5e8 point x pattern x
  // iteration units) refuses what would run for hours. The message gives
  // the estimate measured here (EstimateFit).
  const double work = points * patterns * std::max(maxIter, 1);
  const double workBudget = 1.5e8;
  if (work > workBudget && !translucency::GetLongRunsAllowed())
  {
    const double dims[3] = { static_cast<double>(grid[0]), static_cast<double>(grid[1]),
      static_cast<double>(grid[2]) };
    const FitEstimate estimate = EstimateFit(o, dims, static_cast<int>(patterns));
    throw UsageError("acquire: --grid " + gridArg + " (" + translucency::FormatNumber(points) +
      " points) with --patterns " + patternsArg + " (" + translucency::FormatNumber(patterns) +
      " patterns) and --max-iter " + std::to_string(maxIter) + " is " +
      translucency::FormatNumber(work) + " point x pattern x iteration units, above the budget of " +
      translucency::FormatNumber(workBudget) + " (the fit would take " +
      DescribeEstimate(estimate) + "): use a coarser --grid, fewer --patterns or a lower --max-iter (or " +
      translucency::LongRunOverride() + ")");
  }
}

/// Acquire, synthetic mode: the measurements made from the truth (written to
/// PREFIX_measurements.vtu); the columns of the pattern mosaic in
/// `patternCols`, the element array defaulted to the voxels.
vtkSmartPointer<vtkUnstructuredGrid> MakeSyntheticInput(const AcquireOptions& o, Synthetic& syn,
  int& patternCols, std::string& elementArray)
{
  const std::vector<int> grid = ParseDims(o.GridArg, "--grid", 3);
  const std::vector<int> rc = ParseDims(o.PatternsArg, "--patterns (synthetic mode)", 2);
  patternCols = rc[1];
  CheckSyntheticBudget(o, grid, rc);
  if (o.SetupName == "back")
    syn.Setup = translucency::AcquisitionSetup::Back;
  else if (o.SetupName == "front")
    syn.Setup = translucency::AcquisitionSetup::Front;
  else
    throw UsageError("acquire: --setup must be back or front");
  const int dims[3] = { grid[0], grid[1], grid[2] };
  vtkSmartPointer<vtkUnstructuredGrid> input =
    BuildSynthetic(o.TruthPath, dims, rc[0], rc[1], o.Noise, o.Seed, syn);
  if (elementArray.empty())
    elementArray = "VoxelId";
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  std::string error;
  if (!WriteAtomically(writer, input, o.OutputPrefix + "_measurements.vtu", error))
    throw translucency::Error(error);
  return input;
}

/// Acquire: the inverse diffusion filter on the measurements, with a
/// progress bar on stderr (not with --quiet); its errors, collected by
/// `messages` (which the caller keeps as long as the filter), thrown. The
/// fit's time in `fitMs`, the CPU time of the process during it in `fitCpu`.
vtkSmartPointer<vtkInverseDiffusion> RunInverse(const AcquireOptions& o,
  vtkUnstructuredGrid* input, const std::string& elementArray,
  const std::vector<double>& initialMu, const std::vector<double>& initialSigma,
  MessageCollector& messages, double& fitMs, double& fitCpu)
{
  const int homogeneousMethod = o.HomogeneousFit == "cg" ? vtkInverseDiffusion::CONJUGATE_GRADIENT
                                                         : vtkInverseDiffusion::GAUSS_NEWTON;
  auto inverse = vtkSmartPointer<vtkInverseDiffusion>::New();
  inverse->SetInputData(input);
  inverse->SetLambda(o.Lambda);
  inverse->SetMaxIterations(o.MaxIter);
  inverse->SetRelativeThreshold(o.Threshold);
  inverse->SetInitialAbsorption(initialMu.data());
  inverse->SetInitialReducedScattering(initialSigma.data());
  inverse->SetHomogeneousMethod(homogeneousMethod);
  inverse->SetGaussNewtonLineSearch(o.LineSearchStart == "gauss-newton");
  inverse->SetElementArrayName(elementArray.c_str());
  messages.Watch(inverse, "inverse diffusion");
  vtkNew<vtkCallbackCommand> progress;
  int lastPercent = -1;
  progress->SetClientData(&lastPercent);
  progress->SetCallback([](vtkObject* caller, unsigned long, void* client, void*) {
    const double f = static_cast<vtkAlgorithm*>(caller)->GetProgress();
    int& last = *static_cast<int*>(client);
    const int percent = static_cast<int>(100 * f + 0.5);
    if (percent == last)
      return;
    last = percent;
    const int width = 40, done = static_cast<int>(f * width + 0.5);
    std::cerr << "\racquire [" << std::string(done, '#') << std::string(width - done, '.') << "] "
              << static_cast<int>(100 * f + 0.5) << "%" << std::flush;
  });
  if (!IsQuiet()) // --quiet: no progress bar
    inverse->AddObserver(vtkCommand::ProgressEvent, progress);
  const auto fitStart = Clock::now();
  const double cpuStart = ProcessCpuSeconds();
  inverse->Update();
  fitCpu = ProcessCpuSeconds() - cpuStart;
  inverse->RemoveObserver(progress); // it points at this function's lastPercent
  if (!IsQuiet())
    std::cerr << "\n";
  if (!messages.Errors.empty())
    throw translucency::Error(messages.Last());
  fitMs = MillisecondsSince(fitStart);
  return inverse;
}

/// Acquire, summary: the number of patterns of the result and the relative
/// RMS misfit of the fitted radiance on the observed points (0 without data).
double FitMisfit(vtkPointData* pd, int& numPatterns)
{
  double num = 0.0, den = 0.0;
  numPatterns = 0;
  while (pd->GetArray(Indexed("Radiance", numPatterns).c_str()))
    ++numPatterns;
  for (int m = 0; m < numPatterns; ++m)
  {
    vtkDataArray* l = pd->GetArray(Indexed("Radiance", m).c_str());
    vtkDataArray* f = pd->GetArray(Indexed("FittedRadiance", m).c_str());
    vtkDataArray* mask = pd->GetArray(Indexed("ObservedMask", m).c_str());
    if (!mask)
      mask = pd->GetArray("ObservedMask");
    if (!l || !f)
      continue;
    for (vtkIdType i = 0; i < l->GetNumberOfTuples(); ++i)
    {
      if (mask ? mask->GetComponent(i, 0) == 0.0 : f->GetComponent(i, 1) == 0.0)
        continue;
      for (int c = 0; c < 3; ++c)
      {
        const double d = f->GetComponent(i, c) - l->GetComponent(i, c);
        num += d * d;
        den += l->GetComponent(i, c) * l->GetComponent(i, c);
      }
    }
  }
  return den > 0 ? std::sqrt(num / den) : 0.0;
}

/// Acquire, report: the counts and costs of the inverse run's passes.
void ReportInverseCosts(vtkInverseDiffusion* inverse, double fitMs, json& report)
{
  report["seconds_fit"] = fitMs / 1000.0;
  report["evaluations"] = inverse->GetNumberOfEvaluations();
  report["gradients"] = inverse->GetNumberOfGradients();
  report["tangents"] = inverse->GetNumberOfTangents();
  report["seconds_per_tangent_pass"] =
    inverse->GetNumberOfTangents() > 0 ? inverse->GetTangentSeconds() / inverse->GetNumberOfTangents() : 0.0;
}

/// Acquire, report: the forward and adjoint pass times (a gradient = one
/// forward pass, factorisation + M solves, + one adjoint pass, M solves).
void ReportPassTimes(vtkInverseDiffusion* inverse, json& report)
{
  const double perEvaluation =
    inverse->GetNumberOfEvaluations() > 0 ? inverse->GetEvaluationSeconds() / inverse->GetNumberOfEvaluations() : 0.0;
  const double perAdjoint =
    inverse->GetNumberOfGradients() > 0 ? inverse->GetGradientSeconds() / inverse->GetNumberOfGradients() : 0.0;
  report["seconds_per_forward_pass"] = perEvaluation;
  report["seconds_per_adjoint_pass"] = perAdjoint;
  report["seconds_per_gradient"] = perEvaluation + perAdjoint;
}

/// Acquire: per channel, the objective history of the fit (JSON rows and
/// the plot series) with its final value against the threshold.
json ChannelHistories(vtkTable* history, double threshold, std::vector<PlotSeries>& series)
{
  json channels = json::array();
  series.assign(3, PlotSeries());
  const char* channelNames[3] = { "R", "G", "B" };
  for (int c = 0; c < 3; ++c)
  {
    series[c].Name = std::string("objective ") + channelNames[c];
    json rows = json::array();
    for (vtkIdType r = 0; history && r < history->GetNumberOfRows(); ++r)
    {
      if (history->GetValueByName(r, "Channel").ToInt() != c)
        continue;
      const double objective = history->GetValueByName(r, "Objective").ToDouble();
      series[c].X.push_back(static_cast<double>(series[c].X.size()));
      series[c].Y.push_back(objective);
      rows.push_back({ { "stage", history->GetValueByName(r, "Stage").ToInt() == 0 ? "homogeneous" : "heterogeneous" },
        { "iteration", history->GetValueByName(r, "Iteration").ToInt() },
        { "objective", objective },
        { "gradient_norm", history->GetValueByName(r, "GradientNorm").ToDouble() },
        { "step", history->GetValueByName(r, "Step").ToDouble() },
        { "evaluations", history->GetValueByName(r, "Evaluations").ToInt() } });
    }
    json ch;
    ch["channel"] = channelNames[c];
    ch["final_objective"] = series[c].Y.empty() ? 0.0 : series[c].Y.back();
    ch["converged"] = !series[c].Y.empty() && series[c].Y.back() < threshold;
    ch["history"] = rows;
    channels.push_back(ch);
  }
  return channels;
}

/// Acquire, synthetic mode: the recovered coefficients against the truth by
/// depth in the report and, with pictures, the radiance and slice mosaics.
void ReportAgainstTruth(const AcquireOptions& o, const Synthetic& syn,
  vtkUnstructuredGrid* result, int numPatterns, int patternCols, json& report)
{
  // Recovered per voxel (every tet of a voxel holds its values).
  const int numVoxels = syn.N[0] * syn.N[1] * syn.N[2];
  vtkDataArray* kappaArray = result->GetCellData()->GetArray("DiffusionCoefficient");
  vtkDataArray* muArray = result->GetCellData()->GetArray("AbsorptionCoefficient");
  std::vector<double> kappa(3 * numVoxels), mu(3 * numVoxels);
  for (int v = 0; v < numVoxels; ++v)
    for (int c = 0; c < 3; ++c)
    {
      kappa[3 * v + c] = kappaArray->GetComponent(6 * v, c);
      mu[3 * v + c] = muArray->GetComponent(6 * v, c);
    }
  json depths = json::array();
  for (int k : SliceLayers(syn))
  {
    std::vector<double> tk, rk, tm, rm;
    for (int v = k * syn.N[0] * syn.N[1]; v < (k + 1) * syn.N[0] * syn.N[1]; ++v)
    {
      tk.push_back(syn.Kappa[3 * v + 1]);
      rk.push_back(kappa[3 * v + 1]);
      tm.push_back(syn.Mu[3 * v + 1]);
      rm.push_back(mu[3 * v + 1]);
    }
    // null where the truth is constant on the layer (no correlation defined).
    const double ck = Correlation(tk, rk), cm = Correlation(tm, rm);
    depths.push_back({ { "layer", k },
      { "kappa_correlation_G", std::isfinite(ck) ? json(ck) : json(nullptr) },
      { "mua_correlation_G", std::isfinite(cm) ? json(cm) : json(nullptr) } });
  }
  report["truth_correlation_by_depth"] = depths;
  report["grid"] = { syn.N[0], syn.N[1], syn.N[2] };
  report["setup"] = o.SetupName;
  report["noise"] = o.Noise;
  if (o.NoPng)
    return;
  vtkPointData* pd = result->GetPointData();
  std::vector<std::vector<double>> fitted(numPatterns);
  for (int m = 0; m < numPatterns; ++m)
  {
    vtkDataArray* f = pd->GetArray(Indexed("FittedRadiance", m).c_str());
    fitted[m].resize(3 * f->GetNumberOfTuples());
    for (vtkIdType i = 0; i < f->GetNumberOfTuples(); ++i)
      for (int c = 0; c < 3; ++c)
        fitted[m][3 * i + c] = f->GetComponent(i, c);
  }
  std::string error;
  if (!WriteRadianceMosaic(syn, fitted, patternCols, o.OutputPrefix + "_radiance.png", error) ||
    !WriteSliceMosaic(syn, kappa, mu, o.OutputPrefix + "_slices.png", error))
    throw translucency::Error(error);
}

/// Acquire: the plot of the objective histories. Needs an X server
/// (xvfb-run): a failure only warns.
void WriteObjectivePlot(const std::vector<PlotSeries>& series, const std::string& outputPrefix)
{
  std::string plotError;
  if (!OpenPictureDisplay("--no-png", plotError))
    std::cerr << "translucency: warning: objective plot not written: " << plotError << "\n";
  else if (!WritePlotPNG(series, "iteration (homogeneous fit, then heterogeneous)",
        "normalised objective", outputPrefix + "_objective.png", plotError))
    std::cerr << "translucency: warning: objective plot not written: " << plotError << "\n";
}

/// Acquire, on stdout: the summary line, each channel's final objective and
/// the stage times.
void PrintAcquireSummary(const json& report, int numPatterns, vtkUnstructuredGrid* result,
  vtkInverseDiffusion* inverse, const std::vector<Stage>& stages, const std::string& outputPrefix)
{
  const json& channels = report["channels"];
  const char* channelNames[3] = { "R", "G", "B" };
  std::cout << "acquire: " << numPatterns << " patterns, " << result->GetNumberOfCells()
            << " tets; fitted radiance relative RMS " << report["fit_relative_rms"].get<double>()
            << "; " << inverse->GetNumberOfEvaluations() << " forward passes, "
            << inverse->GetNumberOfGradients() << " adjoint passes, "
            << inverse->GetNumberOfTangents() << " tangent passes\n";
  for (int c = 0; c < 3; ++c)
    std::cout << "  channel " << channelNames[c] << ": objective "
              << channels[c]["final_objective"].get<double>()
              << (channels[c]["converged"].get<bool>() ? " (below threshold)" : " (not below threshold)")
              << "\n";
  PrintStages(stages);
  std::cout << "wrote " << outputPrefix << ".vtu\n";
}

int Acquire(const AcquireOptions& o)
{
  const std::string& outputPrefix = o.OutputPrefix;
  const bool synthetic = !o.TruthPath.empty(), png = !o.NoPng;
  std::vector<double> initialMu, initialSigma;
  CheckAcquireOptions(o, initialMu, initialSigma);
  OutputPlan plan; // its locks last until the end of the run
  PlanAcquireOutputs(o, plan);

  // The measurements: synthetic from a truth, or read with their patterns.
  const auto start = Clock::now();
  std::vector<Stage> stages;
  Synthetic syn;
  int patternCols = 1;
  std::string elementArray = o.ElementArray;
  vtkSmartPointer<vtkUnstructuredGrid> input;
  if (synthetic)
  {
    input = MakeSyntheticInput(o, syn, patternCols, elementArray);
    stages.push_back({ "synthetic measurements", MillisecondsSince(start) });
  }
  else
  {
    input = ReadGrid(o.SamplePath);
    AttachPatterns(input, o.PatternsArg);
    CheckMeasurementsFinite(input, o.PatternsArg);
    if (elementArray.empty() && input->GetCellData()->GetArray("VoxelId"))
      elementArray = "VoxelId";
    stages.push_back({ "read", MillisecondsSince(start) });
  }

  // What the fit will cost if every iteration runs, measured here (stderr).
  const FitEstimate estimate = EstimateInputFit(o, input, synthetic);
  if (!IsQuiet())
    std::cerr << "acquire: estimate: " << DescribeEstimate(estimate) << "\n";

  double fitMs = 0.0, fitCpu = 0.0;
  MessageCollector messages;
  vtkSmartPointer<vtkInverseDiffusion> inverse =
    RunInverse(o, input, elementArray, initialMu, initialSigma, messages, fitMs, fitCpu);
  stages.push_back({ "inverse diffusion", fitMs });
  vtkUnstructuredGrid* result = inverse->GetOutput();
  vtkTable* history = vtkTable::SafeDownCast(inverse->GetHistoryOutput());

  // No exit 0 with NaN: the recovered coefficients and fitted radiance
  // must be finite before anything is written.
  RequireFiniteResult(result, "the recovered material");
  std::string error;
  {
    vtkNew<vtkXMLUnstructuredGridWriter> writer;
    if (!WriteAtomically(writer, result, outputPrefix + ".vtu", error))
      throw translucency::Error(error);
  }

  // Summary: misfit of the fitted radiance on the observed points.
  int numPatterns = 0;
  const double misfit = FitMisfit(result->GetPointData(), numPatterns);
  json report;
  report["command"] = "acquire";
  report["provenance"] = Provenance(o.App);
  report["provenance"]["seed"] = o.Seed;
  report["mode"] = synthetic ? "synthetic" : "files";
  report["patterns"] = numPatterns;
  report["lambda"] = o.Lambda;
  report["max_iter"] = o.MaxIter;
  report["factorization"] = translucency::DiffusionForwardModel::GetFactorizationName();
  report["points"] = result->GetNumberOfPoints();
  report["tets"] = result->GetNumberOfCells();
  report["fit_relative_rms"] = misfit;
  ReportInverseCosts(inverse, fitMs, report);
  ReportEstimate(estimate, fitCpu, report);
  report["homogeneous_fit"] = o.HomogeneousFit == "cg" ? "cg" : "gauss-newton";
  report["line_search_start"] =
    o.LineSearchStart == "gauss-newton" ? "gauss-newton" : "previous";
  ReportPassTimes(inverse, report);
  std::vector<PlotSeries> series;
  report["channels"] = ChannelHistories(history, o.Threshold, series);

  if (synthetic)
    ReportAgainstTruth(o, syn, result, numPatterns, patternCols, report);
  if (png)
    WriteObjectivePlot(series, outputPrefix);
  json timing = json::array();
  for (const Stage& s : stages)
    timing.push_back({ { "stage", s.Name }, { "ms", s.Milliseconds } });
  report["timing"] = timing;
  if (!o.JsonPath.empty())
  {
    EnsureParentDirectory(o.JsonPath);
    if (!WriteText(o.JsonPath, report.dump(2) + "\n", error))
      throw translucency::Error(error);
  }
  PrintAcquireSummary(report, numPatterns, result, inverse, stages, outputPrefix);
  return 0;
}

} // namespace

Command AddAcquireCommand(CLI::App& app)
{
  auto o = std::make_shared<AcquireOptions>();
  CLI::App* c = app.add_subcommand("acquire",
    "Recover kappa and mu_a from measured radiance (inverse diffusion).\n\n"
    "Polygrid Sec. 4: per-element kappa and mu_a whose forward diffusion\n"
    "reproduces the measured radiance under M light patterns. Synthetic mode\n"
    "(--synthetic-truth) makes the measurements from a known volume and also\n"
    "writes PREFIX_measurements.vtu (reusable with --sample/--patterns),\n"
    "PREFIX_radiance.png and PREFIX_slices.png."
    "\n\nusage: translucency acquire --sample FILE --patterns DIR|FILE --output PREFIX [options]\n"
           "   or: translucency acquire --synthetic-truth FILE --grid NXxNYxNZ --patterns RxC "
           "--output PREFIX [options]");
  o->App = c;
  c->add_option("--sample", o->SamplePath, "tet mesh (.vtu), optional RefractiveIndex cell array")
    ->type_name("FILE");
  c->add_option("--patterns", o->PatternsArg,
     "FILE: .vtu on the same points with Irradiance_<k>, Radiance_<k>\n"
     "(3 components each, k = 0..M-1) and optional\n"
     "ObservedMask_<k> or ObservedMask point arrays;\n"
     "DIR: one .vtu per pattern (sorted by name), each with\n"
     "Irradiance, Radiance and optional ObservedMask;\n"
     "RxC (synthetic mode): lit face z = zmin split into RxC\n"
     "regions lit one at a time")
    ->type_name("DIR|FILE|RxC")
    ->required();
  c->add_option("--element-array", o->ElementArray,
     "cell array grouping tets that share parameters\n"
     "(default: VoxelId if present, else one per tet)")
    ->type_name("NAME");
  c->add_option("--output", o->OutputPrefix,
     "writes PREFIX.vtu (recovered material), PNGs\n"
     "(synthetic mode) and PREFIX_objective.png")
    ->type_name("PREFIX")
    ->required();
  AddNumber(c, "--lambda", o->Lambda, "regulariser weight", "L", [](double l) { return l >= 0; },
    "acquire: --lambda must be >= 0");
  AddNumber(c, "--max-iter", o->MaxIter, "CG iterations per channel", "N",
    [](double n) { return n >= 0; }, "acquire: --max-iter must be >= 0");
  AddNumber(c, "--threshold", o->Threshold, "stop when misfit < T x sum of measured L^2", "T");
  AddNumberList(c, "--initial-mua", o->InitialMu, "homogeneous initial guess, 1/mm (1 or 3 values)",
    "R,G,B");
  AddNumberList(c, "--initial-sigmas", o->InitialSigma,
    "homogeneous initial guess, 1/mm (1 or 3 values)", "R,G,B");
  c->add_option("--homogeneous-fit", o->HomogeneousFit,
     "how the initial homogeneous pair is fitted: Levenberg-\n"
     "Marquardt on tangent solves or the paper's CG")
    ->type_name("gauss-newton|cg")
    ->capture_default_str()
    ->check(OneOf("--homogeneous-fit", { "gauss-newton", "cg" }));
  c->add_option("--line-search-start", o->LineSearchStart,
     "trial step of each golden-section search: the Gauss-\n"
     "Newton minimiser along d or the previous step")
    ->type_name("gauss-newton|previous")
    ->capture_default_str()
    ->check(OneOf("--line-search-start", { "gauss-newton", "previous" }));
  c->add_option("--json", o->JsonPath, "timings and results")->type_name("FILE");
  c->add_flag("--no-png", o->NoPng, "skip the pictures");
  // Synthetic mode: measurements made here from a known volume, no camera;
  // also writes PREFIX_measurements.vtu (reusable with --sample/--patterns),
  // PREFIX_radiance.png and PREFIX_slices.png (see the description).
  const std::string synthetic = "Synthetic mode (measurements made here from a known volume)";
  c->add_option("--synthetic-truth", o->TruthPath,
     ".vti or .vtu with AbsorptionCoefficient and\n"
     "ReducedScatteringCoefficient (3 components, cell or\n"
     "point data; optional RefractiveIndex, else 1.3);\n"
     "its bounds are the sample block")
    ->type_name("FILE")
    ->group(synthetic);
  c->add_option("--grid", o->GridArg, "voxels of the block (parameters per voxel)")
    ->type_name("NXxNYxNZ")
    ->check(CLI::Validator(
      [](std::string& text) {
        ParseDims(text, "--grid", 3);
        return std::string();
      },
      ""))
    ->group(synthetic);
  c->add_option("--setup", o->SetupName,
     "back: measure the face z = zmax; front: measure the\n"
     "unlit points of the lit face")
    ->type_name("back|front")
    ->capture_default_str()
    ->check(OneOf("--setup", { "back", "front" }))
    ->group(synthetic);
  AddNumber(c, "--noise", o->Noise, "Gaussian noise, SIGMA x the pattern's maximum radiance",
    "SIGMA", [](double n) { return n >= 0; }, "acquire: --noise must be >= 0")
    ->group(synthetic);
  AddNumber(c, "--seed", o->Seed, "noise seed", "N")->group(synthetic);
  return { c, [o]() { return Acquire(*o); } };
}

} // namespace translucency_app
