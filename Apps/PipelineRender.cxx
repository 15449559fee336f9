#include "PipelineRender.h"

#include <vtkActor.h>
#include <vtkAxis.h>
#include <vtkChartLegend.h>
#include <vtkChartXY.h>
#include <vtkContextScene.h>
#include <vtkContextView.h>
#include <vtkDoubleArray.h>
#include <vtkPlot.h>
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
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkWindowToImageFilter.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace translucency_app
{
namespace
{
double SRGB(double v)
{
  v = std::min(1.0, std::max(0.0, v));
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

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
  const std::string tmp = fileName + ".tmp.png";
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(tmp.c_str());
  writer->SetInputConnection(grab->GetOutputPort());
  writer->Write();
  if (writer->GetErrorCode() != 0)
  {
    std::remove(tmp.c_str());
    error = "cannot write " + fileName;
    return false;
  }
  if (std::rename(tmp.c_str(), fileName.c_str()) != 0)
  {
    std::remove(tmp.c_str());
    error = "cannot rename the temporary image to " + fileName;
    return false;
  }
  return true;
}

double ToneMapRadiance(vtkPolyData* surface, double exposure)
{
  vtkDataArray* radiance = surface->GetPointData()->GetArray("Radiance");
  const vtkIdType n = surface->GetNumberOfPoints();
  if (exposure <= 0.0)
  {
    std::vector<double> peaks(static_cast<size_t>(n));
    for (vtkIdType i = 0; i < n; ++i)
    {
      peaks[i] = std::max(
        { radiance->GetComponent(i, 0), radiance->GetComponent(i, 1), radiance->GetComponent(i, 2) });
    }
    double p99 = 1.0;
    if (n > 0)
    {
      const size_t k = static_cast<size_t>(0.99 * (n - 1));
      std::nth_element(peaks.begin(), peaks.begin() + k, peaks.end());
      p99 = peaks[k];
    }
    exposure = p99 > 0 ? 0.9 / p99 : 1.0;
  }
  vtkNew<vtkUnsignedCharArray> rgb;
  rgb->SetName("RadianceRGB");
  rgb->SetNumberOfComponents(3);
  rgb->SetNumberOfTuples(n);
  for (vtkIdType i = 0; i < n; ++i)
  {
    for (int c = 0; c < 3; ++c)
    {
      rgb->SetTypedComponent(i, c,
        static_cast<unsigned char>(std::lround(255.0 * SRGB(exposure * radiance->GetComponent(i, c)))));
    }
  }
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
  vtkNew<vtkRenderWindow> window;
  window->SetOffScreenRendering(1);
  window->SetMultiSamples(0);
  window->AddRenderer(renderer);
  window->SetSize(options.Width, options.Height);
  PlaceCamera(renderer, surface->GetBounds(), options);
  return Snapshot(window, fileName, error);
}

bool WriteFluenceSlicePNG(vtkUnstructuredGrid* mesh, const RadianceImageOptions& options,
  const std::string& fileName, std::string& error)
{
  double bounds[6];
  mesh->GetBounds(bounds);
  const double center[3] = { 0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]),
    0.5 * (bounds[4] + bounds[5]) };
  vtkNew<vtkPlane> plane;
  plane->SetOrigin(center);
  plane->SetNormal(options.ViewDirection);
  vtkNew<vtkCutter> cutter;
  cutter->SetInputData(mesh);
  cutter->SetCutFunction(plane);
  cutter->GenerateTrianglesOn();
  cutter->Update();
  vtkPolyData* slice = cutter->GetOutput();
  if (slice->GetNumberOfPoints() == 0)
  {
    error = "the slice through the centre of the mesh is empty";
    return false;
  }
  vtkDataArray* fluence = slice->GetPointData()->GetArray("Fluence");
  if (!fluence)
  {
    error = "the mesh has no Fluence array to slice";
    return false;
  }
  double range[2];
  fluence->GetRange(range, 0);
  const double hi = std::max(range[1], 1e-300);
  const double lo = std::max(range[0], hi * 1e-4);
  vtkNew<vtkLookupTable> lut;
  lut->SetScaleToLog10();
  lut->SetTableRange(lo, hi);
  lut->SetHueRange(0.667, 0.0);
  lut->SetNumberOfTableValues(256);
  lut->Build();
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(slice);
  mapper->SetLookupTable(lut);
  mapper->SetScalarModeToUsePointFieldData();
  mapper->SelectColorArray("Fluence");
  mapper->ColorByArrayComponent("Fluence", 0);
  mapper->SetUseLookupTableScalarRange(true);
  mapper->ScalarVisibilityOn();
  vtkNew<vtkActor> actor;
  actor->SetMapper(mapper);
  actor->GetProperty()->LightingOff();

  // The object's silhouette for context.
  vtkNew<vtkDataSetSurfaceFilter> surfaceFilter;
  surfaceFilter->SetInputData(mesh);
  vtkNew<vtkPolyDataMapper> surfaceMapper;
  surfaceMapper->SetInputConnection(surfaceFilter->GetOutputPort());
  surfaceMapper->ScalarVisibilityOff();
  vtkNew<vtkActor> surfaceActor;
  surfaceActor->SetMapper(surfaceMapper);
  surfaceActor->GetProperty()->SetOpacity(0.15);
  surfaceActor->GetProperty()->SetColor(0.8, 0.8, 0.8);

  vtkNew<vtkScalarBarActor> bar;
  bar->SetLookupTable(lut);
  bar->SetTitle("Fluence R (W/mm^2)");
  bar->SetNumberOfLabels(5);
  bar->SetLabelFormat("%.1e");
  bar->SetPosition(0.84, 0.1);
  bar->SetPosition2(0.14, 0.8);
  bar->GetTitleTextProperty()->SetFontSize(14);
  bar->GetLabelTextProperty()->SetFontSize(12);
  bar->UnconstrainedFontSizeOn();

  vtkNew<vtkRenderer> renderer;
  renderer->AddActor(actor);
  renderer->AddActor(surfaceActor);
  renderer->AddViewProp(bar);
  renderer->SetBackground(0.08, 0.08, 0.1);
  vtkNew<vtkRenderWindow> window;
  window->SetOffScreenRendering(1);
  window->SetMultiSamples(0);
  window->AddRenderer(renderer);
  window->SetSize(options.Width, options.Height);
  PlaceCamera(renderer, bounds, options);
  return Snapshot(window, fileName, error);
}

bool WriteScalarMapPNG(vtkPolyData* surface, const char* arrayName, double lo, double hi,
  const std::string& title, const RadianceImageOptions& options, const std::string& fileName,
  std::string& error)
{
  if (!surface->GetPointData()->GetArray(arrayName))
  {
    error = std::string("no point array '") + arrayName + "' to render";
    return false;
  }
  vtkNew<vtkLookupTable> lut;
  lut->SetTableRange(lo, hi > lo ? hi : lo + 1e-12);
  lut->SetHueRange(0.667, 0.0);
  lut->SetNumberOfTableValues(256);
  lut->Build();
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
  vtkNew<vtkScalarBarActor> bar;
  bar->SetLookupTable(lut);
  bar->SetTitle(title.c_str());
  bar->SetNumberOfLabels(5);
  bar->SetLabelFormat("%.3g");
  bar->SetPosition(0.84, 0.1);
  bar->SetPosition2(0.14, 0.8);
  bar->GetTitleTextProperty()->SetFontSize(14);
  bar->GetLabelTextProperty()->SetFontSize(12);
  bar->UnconstrainedFontSizeOn();
  vtkNew<vtkRenderer> renderer;
  renderer->AddActor(actor);
  renderer->AddViewProp(bar);
  renderer->SetBackground(0.08, 0.08, 0.1);
  vtkNew<vtkRenderWindow> window;
  window->SetOffScreenRendering(1);
  window->SetMultiSamples(0);
  window->AddRenderer(renderer);
  window->SetSize(options.Width, options.Height);
  PlaceCamera(renderer, surface->GetBounds(), options);
  return Snapshot(window, fileName, error);
}

bool WritePlotPNG(const std::vector<PlotSeries>& series, const std::string& xTitle,
  const std::string& yTitle, const std::string& fileName, std::string& error)
{
  vtkNew<vtkContextView> view;
  view->GetRenderWindow()->SetOffScreenRendering(1);
  view->GetRenderWindow()->SetSize(800, 600);
  view->GetRenderer()->SetBackground(1.0, 1.0, 1.0);
  vtkNew<vtkChartXY> chart;
  view->GetScene()->AddItem(chart);
  chart->SetShowLegend(true);
  chart->GetAxis(vtkAxis::BOTTOM)->SetTitle(xTitle);
  chart->GetAxis(vtkAxis::LEFT)->SetTitle(yTitle);
  chart->GetAxis(vtkAxis::LEFT)->SetLogScale(true);
  static const unsigned char colours[][3] = { { 31, 119, 180 }, { 255, 127, 14 },
    { 44, 160, 44 }, { 214, 39, 40 }, { 148, 103, 189 }, { 140, 86, 75 } };
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
    vtkPlot* line = chart->AddPlot(vtkChart::LINE);
    line->SetInputData(table, 0, 1);
    const unsigned char* c = colours[k++ % 6];
    line->SetColor(c[0], c[1], c[2], 255);
    line->SetWidth(2.0);
  }
  if (tables.empty())
  {
    error = "nothing to plot";
    return false;
  }
  return Snapshot(view->GetRenderWindow(), fileName, error);
}

} // namespace translucency_app
