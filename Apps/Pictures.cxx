#include "Pictures.h"

#include "Error.h"

#include <vtkColorTransferFunction.h>
#include <vtkImageData.h>
#include <vtkLookupTable.h>
#include <vtkCoordinate.h>
#include <vtkNew.h>
#include <vtkPropAssembly.h>
#include <vtkRenderWindow.h>
#include <vtkScalarBarActor.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkStdString.h>
#include <vtkTextRenderer.h>

#include <algorithm>
#include <chrono>
#include <thread>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>

// Last: Xlib defines macros (None, Status, Bool) that clash with other headers.
#include <X11/Xlib.h>

namespace translucency_app
{
namespace
{
struct SharedDisplay
{
  bool Tried = false;
  Display* Connection = nullptr;
  std::string Error;
};

SharedDisplay& TheDisplay()
{
  static SharedDisplay display;
  return display;
}

// matplotlib's viridis and inferno (CC0) at 17 evenly spaced points.
const double Viridis[17][3] = { { 0.2670, 0.0049, 0.3294 }, { 0.2823, 0.0950, 0.4173 },
  { 0.2788, 0.1755, 0.4834 }, { 0.2590, 0.2515, 0.5247 }, { 0.2297, 0.3224, 0.5457 },
  { 0.1994, 0.3876, 0.5546 }, { 0.1727, 0.4488, 0.5579 }, { 0.1490, 0.5081, 0.5573 },
  { 0.1276, 0.5669, 0.5506 }, { 0.1206, 0.6258, 0.5335 }, { 0.1579, 0.6838, 0.5017 },
  { 0.2461, 0.7389, 0.4520 }, { 0.3692, 0.7889, 0.3829 }, { 0.5160, 0.8312, 0.2943 },
  { 0.6785, 0.8637, 0.1895 }, { 0.8456, 0.8873, 0.0997 }, { 0.9932, 0.9062, 0.1439 } };
const double Inferno[17][3] = { { 0.0015, 0.0005, 0.0139 }, { 0.0423, 0.0281, 0.1411 },
  { 0.1293, 0.0473, 0.2908 }, { 0.2383, 0.0366, 0.3964 }, { 0.3415, 0.0623, 0.4294 },
  { 0.4412, 0.0993, 0.4316 }, { 0.5409, 0.1347, 0.4151 }, { 0.6401, 0.1714, 0.3811 },
  { 0.7357, 0.2159, 0.3302 }, { 0.8224, 0.2752, 0.2661 }, { 0.8943, 0.3534, 0.1936 },
  { 0.9470, 0.4492, 0.1153 }, { 0.9784, 0.5579, 0.0349 }, { 0.9879, 0.6753, 0.0653 },
  { 0.9746, 0.7977, 0.2063 }, { 0.9476, 0.9174, 0.4107 }, { 0.9884, 0.9984, 0.6449 } };
template <size_t N>
void Interpolate(const double (&table)[N][3], double t, double rgb[3])
{
  const double x = t * (N - 1);
  const size_t k = std::min(N - 2, static_cast<size_t>(x));
  const double f = x - k;
  for (int c = 0; c < 3; ++c)
    rgb[c] = (1 - f) * table[k][c] + f * table[k + 1][c];
}
}

bool OpenPictureDisplay(const std::string& skipOption, std::string& error)
{
  SharedDisplay& d = TheDisplay();
  if (!d.Tried)
  {
    d.Tried = true;
    const char* name = std::getenv("DISPLAY");
    const std::string advice = "; run under an X server, e.g. `xvfb-run -a translucency ...`" +
      (skipOption.empty() ? std::string() : ", or pass " + skipOption + " to skip the pictures") +
      " (this VTK build renders through GLX only)";
    if (!name || !*name)
      d.Error = "no X display for the pictures (DISPLAY is not set)" + advice;
    else
    {
      // A server resetting after its last client left (another program's
      // pictures just finished) drops new connections for a moment: retry.
      for (int attempt = 0; attempt < 5 && !d.Connection; ++attempt)
      {
        if (attempt > 0)
          std::this_thread::sleep_for(std::chrono::milliseconds(200));
        d.Connection = XOpenDisplay(name);
      }
      if (!d.Connection)
        d.Error = std::string("cannot connect to the X display '") + name + "'" + advice;
    }
  }
  if (!d.Connection)
  {
    error = d.Error;
    return false;
  }
  return true;
}

void RequirePictureDisplay(const std::string& skipOption)
{
  std::string error;
  if (!OpenPictureDisplay(skipOption, error))
    throw translucency::Error(error);
}

void UsePictureDisplay(vtkRenderWindow* window)
{
  // Never a window of its own display: without an X server VTK would abort().
  RequirePictureDisplay(std::string());
  window->SetOffScreenRendering(1);
  window->SetMultiSamples(0);
  // A window given a display does not close it: the connection outlives it.
  window->SetDisplayId(TheDisplay().Connection);
}

vtkSmartPointer<vtkRenderWindow> NewPictureWindow(int width, int height)
{
  auto window = vtkSmartPointer<vtkRenderWindow>::New();
  UsePictureDisplay(window);
  window->SetSize(width, height);
  return window;
}

void SampleColourMap(ColourMap map, double t, double rgb[3])
{
  t = std::isfinite(t) ? std::min(1.0, std::max(0.0, t)) : 0.0;
  switch (map)
  {
    case ColourMap::Viridis:
      Interpolate(Viridis, t, rgb);
      break;
    case ColourMap::Inferno:
      Interpolate(Inferno, t, rgb);
      break;
    case ColourMap::CoolWarm:
    {
      // Moreland's diverging map, as VTK computes it (blue - grey - red).
      vtkNew<vtkColorTransferFunction> ctf;
      ctf->SetColorSpaceToDiverging();
      ctf->AddRGBPoint(0.0, 0.230, 0.299, 0.754);
      ctf->AddRGBPoint(1.0, 0.706, 0.016, 0.150);
      ctf->GetColor(t, rgb);
      break;
    }
  }
}

vtkSmartPointer<vtkLookupTable> MakeLookupTable(
  ColourMap map, double lo, double hi, bool logScale)
{
  auto table = vtkSmartPointer<vtkLookupTable>::New();
  if (logScale)
  {
    hi = std::max(hi, 1e-300);
    lo = std::min(std::max(lo, 1e-300), hi);
    table->SetScaleToLog10();
  }
  table->SetTableRange(lo, hi > lo ? hi : lo + std::max(1e-12, std::abs(lo) * 1e-9));
  const int n = 256;
  table->SetNumberOfTableValues(n);
  for (int i = 0; i < n; ++i)
  {
    double rgb[3];
    SampleColourMap(map, i / (n - 1.0), rgb);
    table->SetTableValue(i, rgb[0], rgb[1], rgb[2], 1.0);
  }
  table->SetNanColor(0.5, 0.5, 0.5, 1.0);
  return table;
}

vtkSmartPointer<vtkProp> MakeColourBar(
  vtkLookupTable* table, const std::string& quantity, const std::string& unit)
{
  std::string title = quantity;
  if (!unit.empty())
    title += " (" + unit + ")";
  if (table->GetScale() == VTK_SCALE_LOG10)
    title += ", log scale";
  // The bar and its tick labels below it (vtkScalarBarActor), the title a
  // text actor of its own above the bar: the scalar bar actor puts its title
  // on the row of the tick labels when the fonts keep their size, where the
  // two overlapped.
  auto bar = vtkSmartPointer<vtkScalarBarActor>::New();
  bar->SetLookupTable(table);
  bar->SetOrientationToHorizontal();
  bar->SetTitle(" ");
  bar->SetNumberOfLabels(5);
  bar->SetLabelFormat(table->GetScale() == VTK_SCALE_LOG10 ? "%.2g" : "%.3g");
  bar->SetPosition(0.1, 0.01);
  bar->SetPosition2(0.8, 0.10);
  bar->SetBarRatio(0.4);
  bar->SetTextPositionToPrecedeScalarBar(); // horizontal: the labels below the bar
  bar->UnconstrainedFontSizeOn();           // the labels keep their size
  auto caption = vtkSmartPointer<vtkTextActor>::New();
  caption->SetInput(title.c_str());
  caption->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
  caption->GetPositionCoordinate()->SetValue(0.5, 0.115);
  for (vtkTextProperty* text :
    { bar->GetTitleTextProperty(), bar->GetLabelTextProperty(), caption->GetTextProperty() })
  {
    text->SetColor(1.0, 1.0, 1.0);
    text->SetFontFamilyToArial();
    text->BoldOff();
    text->ItalicOff();
    text->ShadowOff();
  }
  bar->GetTitleTextProperty()->SetFontSize(1);
  bar->GetLabelTextProperty()->SetFontSize(13);
  caption->GetTextProperty()->SetFontSize(16);
  caption->GetTextProperty()->SetJustificationToCentered();
  caption->GetTextProperty()->SetVerticalJustificationToBottom();
  auto assembly = vtkSmartPointer<vtkPropAssembly>::New();
  assembly->AddPart(bar);
  assembly->AddPart(caption);
  return assembly;
}

void DrawText(RasterImage image, int x, int y, const std::string& text, int fontSize,
  const unsigned char colour[3])
{
  vtkNew<vtkTextProperty> property;
  property->SetFontSize(fontSize);
  property->SetFontFamilyToArial();
  property->SetColor(colour[0] / 255.0, colour[1] / 255.0, colour[2] / 255.0);
  property->SetJustificationToLeft();
  property->SetVerticalJustificationToTop();
  vtkNew<vtkImageData> rendered;
  int dims[2] = { 0, 0 };
  vtkTextRenderer* renderer = vtkTextRenderer::GetInstance();
  if (!renderer || !renderer->RenderString(property, text, rendered, dims, 72))
    return;
  int extent[6];
  rendered->GetExtent(extent);
  const int w = extent[1] - extent[0] + 1, h = extent[3] - extent[2] + 1;
  auto* rgba = static_cast<unsigned char*>(rendered->GetScalarPointer());
  const int components = rendered->GetNumberOfScalarComponents();
  if (!rgba || components != 4)
    return;
  // The text image's rows go upwards; its top row is the text's top.
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w; ++col)
    {
      const unsigned char* p = rgba + 4 * (static_cast<size_t>(h - 1 - row) * w + col);
      const int px = x + col, py = y + row;
      if (p[3] == 0 || px < 0 || py < 0 || px >= image.Width || py >= image.Height)
        continue;
      unsigned char* q = &(*image.Pixels)[3 * (static_cast<size_t>(py) * image.Width + px)];
      const double a = p[3] / 255.0;
      for (int c = 0; c < 3; ++c)
        q[c] = static_cast<unsigned char>(std::lround((1 - a) * q[c] + a * colour[c]));
    }
}

int ColourBarHeight()
{
  return 16 + 4 + 14 + 4 + 13 + 6;
}

int DrawColourBar(RasterImage image, int x, int y, int width, ColourMap map, double lo, double hi,
  const std::string& quantity, const std::string& unit)
{
  static const unsigned char black[3] = { 0, 0, 0 };
  DrawText(image, x, y, quantity + (unit.empty() ? "" : " (" + unit + ")"), 14, black);
  const int barTop = y + 20, barHeight = 14;
  for (int col = 0; col < width; ++col)
  {
    double rgb[3];
    SampleColourMap(map, width > 1 ? col / (width - 1.0) : 0.0, rgb);
    for (int row = 0; row < barHeight; ++row)
    {
      const int px = x + col, py = barTop + row;
      if (px < 0 || py < 0 || px >= image.Width || py >= image.Height)
        continue;
      unsigned char* q = &(*image.Pixels)[3 * (static_cast<size_t>(py) * image.Width + px)];
      for (int c = 0; c < 3; ++c)
        q[c] = static_cast<unsigned char>(std::lround(255.0 * rgb[c]));
    }
  }
  char text[64];
  const double values[3] = { lo, 0.5 * (lo + hi), hi };
  for (int k = 0; k < 3; ++k)
  {
    std::snprintf(text, sizeof(text), "%.3g", values[k]);
    const int approxWidth = 7 * static_cast<int>(std::string(text).size());
    const int tx = x + k * (width - 1) / 2 - (k == 0 ? 0 : k == 1 ? approxWidth / 2 : approxWidth);
    DrawText(image, tx, barTop + barHeight + 4, text, 12, black);
  }
  return ColourBarHeight();
}

int ChannelIndex(const std::string& name)
{
  if (name.size() != 1)
    return -1;
  switch (std::toupper(static_cast<unsigned char>(name[0])))
  {
    case 'R':
      return 0;
    case 'G':
      return 1;
    case 'B':
      return 2;
    default:
      return -1;
  }
}

} // namespace translucency_app
