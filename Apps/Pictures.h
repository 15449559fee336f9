/**
 * @file Pictures.h
 * @brief What every picture of the command-line tool shares: one X display
 * connection for the whole process, perceptually uniform colour maps and a
 * labelled colour bar.
 *
 * Why one display connection: ParaView 5.11's VTK renders through GLX only
 * (no EGL, no OSMesa: vtkRenderingOpenGLConfigure.h), so every picture needs
 * an X server. A render window that owns its display opens a connection and
 * closes it when it is destroyed. When the last client of an X server
 * disconnects, the server resets (unless started with -noreset, which
 * xvfb-run does not pass); a client connecting during the reset is dropped
 * (ECONNRESET on the setup request) and vtkXOpenGLRenderWindow then calls
 * abort() ("bad X server connection"). `compare` made about eleven windows
 * one after the other, so one picture in ~4 runs hit that window. One
 * connection opened before the first picture and held until exit keeps the
 * server from resetting, and gives a clear message when there is no server.
 */
#pragma once

#include <vtkSmartPointer.h>

#include <string>
#include <vector>

class vtkLookupTable;
class vtkRenderWindow;
class vtkProp;

namespace translucency_app
{

/**
 * Open the X display connection every picture of this process uses (once;
 * later calls only report the first result). It stays open until the
 * process exits. Returns false with a one-line `error` saying what to do
 * (run under `xvfb-run -a`, or skip the pictures with `skipOption`) when
 * DISPLAY is unset or the server cannot be reached.
 */
bool OpenPictureDisplay(const std::string& skipOption, std::string& error);

/// OpenPictureDisplay, throwing translucency::Error with its message.
void RequirePictureDisplay(const std::string& skipOption);

/// Make `window` off-screen and render on the shared display (opened here
/// if no command opened it before; translucency::Error if there is none).
void UsePictureDisplay(vtkRenderWindow* window);

/// A new off-screen render window of `width` x `height` pixels on the shared display.
vtkSmartPointer<vtkRenderWindow> NewPictureWindow(int width, int height);

/// Colour maps: viridis and inferno for magnitudes (perceptually uniform,
/// matplotlib's), cool-warm (Moreland's diverging map) for signed values.
enum class ColourMap
{
  Viridis,
  Inferno,
  CoolWarm
};

/// The colour of `map` at t in [0, 1] (clamped; NaN -> 0), RGB in [0, 1].
void SampleColourMap(ColourMap map, double t, double rgb[3]);

/// A 256-entry lookup table of `map` on [lo, hi] (log10 scale if
/// `logScale`; then lo must be > 0).
vtkSmartPointer<vtkLookupTable> MakeLookupTable(
  ColourMap map, double lo, double hi, bool logScale);

/**
 * A horizontal colour bar along the bottom of the picture (a prop assembly:
 * the bar with its tick labels below it, and the title above it), titled
 * `quantity` + " (" + `unit` + ")" and ", log scale" when the table is
 * logarithmic; font sizes fixed so that the title is never shrunk or cut,
 * and on its own row so that it never runs into the tick labels.
 */
vtkSmartPointer<vtkProp> MakeColourBar(
  vtkLookupTable* table, const std::string& quantity, const std::string& unit);

/**
 * Pictures drawn pixel by pixel (acquire's mosaics; no X needed): an RGB
 * buffer, row 0 at the top. DrawText writes `text` (FreeType, font size in
 * points at 72 dpi, i.e. pixels) with its top-left corner at (x, y) in
 * `colour`; DrawColourBar draws a horizontal bar of `map` on [lo, hi] of
 * `width` pixels at (x, y), labelled with lo, the middle and hi, titled
 * `quantity (unit)` above it, and returns the height it took.
 */
struct RasterImage
{
  int Width = 0, Height = 0;
  std::vector<unsigned char>* Pixels = nullptr;
};
void DrawText(RasterImage image, int x, int y, const std::string& text, int fontSize,
  const unsigned char colour[3]);
int DrawColourBar(RasterImage image, int x, int y, int width, ColourMap map, double lo, double hi,
  const std::string& quantity, const std::string& unit);
/// The height DrawColourBar takes (pixels).
int ColourBarHeight();

/// Channel index of "R", "G" or "B" (any case); -1 otherwise.
int ChannelIndex(const std::string& name);

} // namespace translucency_app
