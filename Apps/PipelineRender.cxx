#include "PipelineRender.h"

#include "OutputFiles.h"
#include "Pictures.h"
#include "ToneMap.h"

#include <vtkActor.h>
#include <vtkAxis.h>
#include <vtkChartLegend.h>
#include <vtkChartXY.h>
#include <vtkContextScene.h>
#include <vtkContextView.h>
#include <vtkDoubleArray.h>
#include <vtkPen.h>
#include <vtkPlot.h>
#include <vtkPlotPoints.h>
#include <vtkTable.h>
#include <vtkCamera.h>
#include <vtkCutter.h>
#include <vtkDataArray.h>
#include <vtkDataSetSurfaceFilter.h>
#include <vtkLookupTable.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPlane.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkWindowToImageFilter.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>
#include <vector>

namespace translucency_app
{
namespace
{
void PlaceCamera(vtkRenderer* renderer, const double bounds[6], const RadianceImageOptions& options)
{
  const double center[3] = { 0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]),
    0.5 * (bounds[4] + bounds[5]) };
  vtkCamera* camera = renderer->GetActiveCamera();
  camera->SetFocalPoint(center);
  camera->SetPosition(center[0] - options.ViewDirection[0], center[1] - options.ViewDirection[1],
    center[2] - options.ViewDirection[2]);
  camera->SetViewUp(options.ViewUp);
  renderer->ResetCamera(bounds);
  camera->Zoom(1.3);
}

}

bool Snapshot(vtkRenderWindow* window, const std::string& fileName, std::string& error)
{
  window->Render();
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(window);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  grab->Update();
  // A unique temporary created exclusively next to the target, renamed over
  // it (OutputFiles.h); removed on a failure or a signal.
  TemporaryFile tmp(fileName);
  if (tmp.Path().empty())
  {
    error = tmp.Error();
    return false;
  }
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(tmp.Path().c_str());
  writer->SetInputConnection(grab->GetOutputPort());
  writer->Write();
  if (writer->GetErrorCode() != 0)
  {
    error = "cannot write " + fileName;
    return false;
  }
  return tmp.Commit(error);
}

double ToneMapRadiance(vtkPolyData* surface, double exposure)
{
  vtkDataArray* radiance = surface->GetPointData()->GetArray("Radiance");
  const vtkIdType n = surface->GetNumberOfPoints();
  std::vector<double> values(3 * static_cast<size_t>(n));
  for (vtkIdType i = 0; i < n; ++i)
  {
    for (int c = 0; c < 3; ++c)
    {
      values[3 * i + c] = radiance->GetComponent(i, c);
    }
  }
  if (exposure <= 0.0)
  {
    exposure = translucency::AutomaticExposure(values);
  }
  const std::vector<unsigned char> bytes = translucency::ToneMap(values, exposure);
  vtkNew<vtkUnsignedCharArray> rgb;
  rgb->SetName("RadianceRGB");
  rgb->SetNumberOfComponents(3);
  rgb->SetNumberOfTuples(n);
  std::copy(bytes.begin(), bytes.end(), rgb->GetPointer(0));
  surface->GetPointData()->AddArray(rgb);
  return exposure;
}

bool WriteRadiancePNG(vtkPolyData* surface, const RadianceImageOptions& options,
  const std::string& fileName, std::string& error)
{
  if (!surface->GetPointData()->GetArray("RadianceRGB"))
  {
    ToneMapRadiance(surface, options.Exposure);
  }
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(surface);
  mapper->SetScalarModeToUsePointFieldData();
  mapper->SelectColorArray("RadianceRGB");
  mapper->SetColorModeToDirectScalars();
  mapper->ScalarVisibilityOn();
  vtkNew<vtkActor> actor;
  actor->SetMapper(mapper);
  actor->GetProperty()->LightingOff(); // the radiance is the appearance
  vtkNew<vtkRenderer> renderer;
  renderer->AddActor(actor);
  renderer->SetBackground(0.08, 0.08, 0.1);
  vtkSmartPointer<vtkRenderWindow> window = NewPictureWindow(options.Width, options.Height);
  window->AddRenderer(renderer);
  PlaceCamera(renderer, surface->GetBounds(), options);
  return Snapshot(window, fileName, error);
}

namespace
{
/// A caption centred at the top of the picture (never shrunk: long text wraps
/// at " | ").
void AddCaption(vtkRenderer* renderer, const std::string& text)
{
  if (text.empty())
    return;
  vtkNew<vtkTextActor> caption;
  caption->SetInput(text.c_str());
  caption->GetTextProperty()->SetFontSize(16);
  caption->GetTextProperty()->SetColor(1.0, 1.0, 1.0);
  caption->GetTextProperty()->SetJustificationToCentered();
  caption->GetTextProperty()->SetVerticalJustificationToTop();
  caption->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
  caption->SetPosition(0.5, 0.97);
  renderer->AddActor2D(caption);
}

const char* ChannelName(int c)
{
  static const char* names[3] = { "R", "G", "B" };
  return names[std::min(2, std::max(0, c))];
}
}

namespace
{
/// One slice picture: the slice plane of `options` (origin, normal) through
/// `mesh`, coloured by component options.Channel of the point array
/// `arrayName` (`map`, log10 scale if `logScale`, else linear from
/// min(0, lo) for magnitudes or on [lo, hi] for signed values), its colour
/// bar "quantity (unit)", a caption and the object's silhouette, into
/// `renderer`; the camera looks along the slice normal.
bool AddSlicePanel(vtkUnstructuredGrid* mesh, const RadianceImageOptions& options,
  const char* arrayName, ColourMap map, bool logScale, bool magnitude,
  const std::string& quantity, const std::string& unit, const std::string& what,
  vtkPolyData* silhouette, vtkRenderer* renderer, std::string& error)
{
  double bounds[6];
  mesh->GetBounds(bounds);
  double origin[3] = { 0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]),
    0.5 * (bounds[4] + bounds[5]) };
  double normal[3] = { options.ViewDirection[0], options.ViewDirection[1],
    options.ViewDirection[2] };
  if (options.SlicePlane.size() == 6)
  {
    std::copy(options.SlicePlane.begin(), options.SlicePlane.begin() + 3, origin);
    std::copy(options.SlicePlane.begin() + 3, options.SlicePlane.end(), normal);
  }
  vtkNew<vtkPlane> plane;
  plane->SetOrigin(origin);
  plane->SetNormal(normal);
  vtkNew<vtkCutter> cutter;
  cutter->SetInputData(mesh);
  cutter->SetCutFunction(plane);
  cutter->GenerateTrianglesOn();
  cutter->Update();
  vtkPolyData* slice = cutter->GetOutput();
  if (slice->GetNumberOfPoints() == 0)
  {
    error = options.SlicePlane.empty()
      ? "the slice through the centre of the mesh is empty"
      : "--slice-plane misses the mesh (bounds " + std::to_string(bounds[0]) + ".." +
        std::to_string(bounds[1]) + ", " + std::to_string(bounds[2]) + ".." +
        std::to_string(bounds[3]) + ", " + std::to_string(bounds[4]) + ".." +
        std::to_string(bounds[5]) + " mm)";
    return false;
  }
  vtkDataArray* values = slice->GetPointData()->GetArray(arrayName);
  if (!values)
  {
    error = std::string("the mesh has no ") + arrayName + " array to slice";
    return false;
  }
  const int channel = options.Channel;
  double range[2];
  values->GetRange(range, channel);
  double lo = range[0], hi = range[1];
  if (magnitude)
  {
    hi = std::max(range[1], 1e-300);
    lo = logScale ? std::max(range[0], hi * 1e-4) : std::min(range[0], 0.0);
  }
  else if (!(hi > lo))
  {
    lo -= 0.5;
    hi += 0.5;
  }
  vtkSmartPointer<vtkLookupTable> lut = MakeLookupTable(map, lo, hi, logScale);
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(slice);
  mapper->SetLookupTable(lut);
  mapper->SetScalarModeToUsePointFieldData();
  mapper->SelectColorArray(arrayName);
  mapper->ColorByArrayComponent(arrayName, channel);
  mapper->SetUseLookupTableScalarRange(true);
  mapper->ScalarVisibilityOn();
  vtkNew<vtkActor> actor;
  actor->SetMapper(mapper);
  actor->GetProperty()->LightingOff();

  // The object's silhouette for context: the caller's boundary surface, else
  // the mesh's, extracted from its structure alone (no array to carry over:
  // 0.1-0.2 s saved at 200k tets with the solved mesh's arrays).
  vtkNew<vtkPolyDataMapper> surfaceMapper;
  if (silhouette)
  {
    surfaceMapper->SetInputData(silhouette);
  }
  else
  {
    vtkNew<vtkUnstructuredGrid> structure;
    structure->CopyStructure(mesh);
    vtkNew<vtkDataSetSurfaceFilter> surfaceFilter;
    surfaceFilter->SetInputData(structure);
    surfaceFilter->Update();
    surfaceMapper->SetInputData(surfaceFilter->GetOutput());
  }
  surfaceMapper->ScalarVisibilityOff();
  vtkNew<vtkActor> surfaceActor;
  surfaceActor->SetMapper(surfaceMapper);
  surfaceActor->GetProperty()->SetOpacity(0.15);
  surfaceActor->GetProperty()->SetColor(0.8, 0.8, 0.8);

  std::ostringstream caption;
  caption << what << " slice, channel " << ChannelName(channel) << ", plane through ("
          << std::setprecision(3) << origin[0] << ", " << origin[1] << ", " << origin[2]
          << ") mm, normal (" << normal[0] << ", " << normal[1] << ", " << normal[2] << ")";
  renderer->AddActor(actor);
  renderer->AddActor(surfaceActor);
  renderer->AddViewProp(
    MakeColourBar(lut, quantity + " " + ChannelName(channel), unit));
  AddCaption(renderer, caption.str());
  renderer->SetBackground(0.08, 0.08, 0.1);
  // Look at the slice face on: along its normal (an up vector not parallel to it).
  RadianceImageOptions view = options;
  std::copy(normal, normal + 3, view.ViewDirection);
  const double n2 = normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2];
  const double dot = normal[0] * view.ViewUp[0] + normal[1] * view.ViewUp[1] +
    normal[2] * view.ViewUp[2];
  const double up2 =
    view.ViewUp[0] * view.ViewUp[0] + view.ViewUp[1] * view.ViewUp[1] + view.ViewUp[2] * view.ViewUp[2];
  if (dot * dot > 0.99 * n2 * up2)
  {
    view.ViewUp[0] = std::abs(normal[2]) < std::abs(normal[0]) ? 0.0 : 1.0;
    view.ViewUp[1] = 0.0;
    view.ViewUp[2] = std::abs(normal[2]) < std::abs(normal[0]) ? 1.0 : 0.0;
  }
  PlaceCamera(renderer, bounds, view);
  return true;
}
} // namespace

bool WriteFluenceSlicePNG(vtkUnstructuredGrid* mesh, const RadianceImageOptions& options,
  const std::string& fileName, std::string& error, vtkPolyData* silhouette)
{
  vtkNew<vtkRenderer> renderer;
  if (!AddSlicePanel(mesh, options, "Fluence", ColourMap::Inferno, options.LogScale, true,
        "Fluence rate", "W/mm^2", "fluence rate", silhouette, renderer, error))
  {
    return false;
  }
  vtkSmartPointer<vtkRenderWindow> window = NewPictureWindow(options.Width, options.Height);
  window->AddRenderer(renderer);
  return Snapshot(window, fileName, error);
}

bool WriteAmplitudePhaseSlicePNG(vtkUnstructuredGrid* mesh, const RadianceImageOptions& options,
  double frequency, const std::string& fileName, std::string& error, vtkPolyData* silhouette)
{
  std::ostringstream hz;
  hz << std::setprecision(4) << frequency / 1e6 << " MHz";
  vtkNew<vtkRenderer> amplitude, phase;
  if (!AddSlicePanel(mesh, options, "FluenceAmplitude", ColourMap::Inferno, options.LogScale,
        true, "Fluence amplitude |Phi|", "W/mm^2", "amplitude at " + hz.str() + ",",
        silhouette, amplitude, error) ||
    !AddSlicePanel(mesh, options, "FluencePhase", ColourMap::Viridis, false, false,
      "Fluence phase arg(Phi)", "rad, < 0: lag", "phase at " + hz.str() + ",", silhouette,
      phase, error))
  {
    return false;
  }
  amplitude->SetViewport(0.0, 0.0, 0.5, 1.0);
  phase->SetViewport(0.5, 0.0, 1.0, 1.0);
  vtkSmartPointer<vtkRenderWindow> window = NewPictureWindow(2 * options.Width, options.Height);
  window->AddRenderer(amplitude);
  window->AddRenderer(phase);
  return Snapshot(window, fileName, error);
}

bool WriteScalarMapPNG(vtkPolyData* surface, const char* arrayName, double lo, double hi,
  const std::string& quantity, const std::string& unit, const std::string& caption,
  const RadianceImageOptions& options, const std::string& fileName, std::string& error)
{
  if (!surface->GetPointData()->GetArray(arrayName))
  {
    error = std::string("no point array '") + arrayName + "' to render";
    return false;
  }
  const bool signedValues = lo < 0 && hi > 0;
  vtkSmartPointer<vtkLookupTable> lut =
    MakeLookupTable(signedValues ? ColourMap::CoolWarm : ColourMap::Viridis, lo, hi, false);
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(surface);
  mapper->SetLookupTable(lut);
  mapper->SetScalarModeToUsePointFieldData();
  mapper->SelectColorArray(arrayName);
  mapper->SetUseLookupTableScalarRange(true);
  mapper->ScalarVisibilityOn();
  vtkNew<vtkActor> actor;
  actor->SetMapper(mapper);
  actor->GetProperty()->LightingOff();
  vtkNew<vtkRenderer> renderer;
  renderer->AddActor(actor);
  renderer->AddViewProp(MakeColourBar(lut, quantity, unit));
  AddCaption(renderer, caption);
  renderer->SetBackground(0.08, 0.08, 0.1);
  vtkSmartPointer<vtkRenderWindow> window = NewPictureWindow(options.Width, options.Height);
  window->AddRenderer(renderer);
  PlaceCamera(renderer, surface->GetBounds(), options);
  return Snapshot(window, fileName, error);
}

bool WritePlotPNG(const std::vector<PlotSeries>& series, const std::string& xTitle,
  const std::string& yTitle, const std::string& fileName, std::string& error,
  const std::string& title)
{
  vtkNew<vtkContextView> view;
  UsePictureDisplay(view->GetRenderWindow());
  view->GetRenderWindow()->SetSize(800, 600);
  view->GetRenderer()->SetBackground(1.0, 1.0, 1.0);
  vtkNew<vtkChartXY> chart;
  view->GetScene()->AddItem(chart);
  chart->SetShowLegend(true);
  if (!title.empty())
  {
    chart->SetTitle(title);
  }
  chart->GetAxis(vtkAxis::BOTTOM)->SetTitle(xTitle);
  chart->GetAxis(vtkAxis::LEFT)->SetTitle(yTitle);
  chart->GetAxis(vtkAxis::LEFT)->SetLogScale(true);
  static const unsigned char colours[][3] = { { 31, 119, 180 }, { 255, 127, 14 },
    { 44, 160, 44 }, { 214, 39, 40 }, { 148, 103, 189 }, { 140, 86, 75 }, { 0, 0, 0 },
    { 120, 120, 120 } };
  int k = 0;
  std::vector<vtkSmartPointer<vtkTable>> tables;
  for (const PlotSeries& s : series)
  {
    if (s.X.empty())
    {
      continue;
    }
    auto table = vtkSmartPointer<vtkTable>::New();
    vtkNew<vtkDoubleArray> x, y;
    x->SetName(xTitle.c_str());
    y->SetName(s.Name.c_str());
    for (size_t i = 0; i < s.X.size(); ++i)
    {
      x->InsertNextValue(s.X[i]);
      y->InsertNextValue(std::max(s.Y[i], 1e-12)); // log scale
    }
    table->AddColumn(x);
    table->AddColumn(y);
    tables.push_back(table);
    vtkPlot* line = chart->AddPlot(s.Markers ? vtkChart::POINTS : vtkChart::LINE);
    line->SetInputData(table, 0, 1);
    // The 6 series colours cycle; PlotBlack and PlotGrey are named.
    const int index = s.Colour == PlotBlack || s.Colour == PlotGrey
      ? s.Colour
      : (s.Colour >= 0 ? s.Colour : k) % 6;
    const unsigned char* c = colours[index];
    ++k;
    line->SetColor(c[0], c[1], c[2], 255);
    line->SetWidth(2.0);
    if (auto* points = vtkPlotPoints::SafeDownCast(line); points && s.Markers)
    {
      points->SetMarkerStyle(s.Dashed ? vtkPlotPoints::DIAMOND : vtkPlotPoints::CIRCLE);
      points->SetMarkerSize(7.0);
    }
    if (s.DashDot)
    {
      line->GetPen()->SetLineType(vtkPen::DASH_DOT_LINE);
    }
    else if (s.Dashed)
    {
      line->GetPen()->SetLineType(vtkPen::DASH_LINE);
    }
  }
  if (tables.empty())
  {
    error = "nothing to plot";
    return false;
  }
  return Snapshot(view->GetRenderWindow(), fileName, error);
}

} // namespace translucency_app
