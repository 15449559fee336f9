"""What a user does in the ParaView GUI, as a script the GUI runs at start-up.

Not a test by itself: Testing/Python/TestParaViewGui.py starts

    paraview --dr --script=ParaViewGuiChain.py

under Xvfb with these environment variables, then checks the exit code, the
marker file and the screenshot:
    TRANSLUCENCY_PLUGIN      the plugin (.so) to load, as Tools > Manage Plugins does
    TRANSLUCENCY_SOURCE_DIR  the repository (for Data/bunny.ply)
    TRANSLUCENCY_GUI_OUT     directory for the screenshot, the results and the marker

1. Loads the plugin and builds the chain on the bunny (3000 tets, hxt with uniform sizing):
   Translucency Surface Reader -> Tetrahedralize Surface -> Assign Scattering
   Coefficients -> Surface Irradiance -> Solve Diffusion -> Outgoing Radiance,
   each shown, the GUI's events processed after each step.
2. Paint Scattering Coefficients, from the Translucency menu, with its
   polyline stroke widget in the panel: created without a warning (the first
   stroke from the input's bounds), the view saved with and without the
   widget and the whole screen dumped (xwd); then two handles, painted along
   the line.
   Then Solve Diffusion the active source (the Properties panel builds its
   widgets, the Linear Solver drop-down included), each Solver chosen in
   the panel and the Linear Solver drop-down's names read back; its tables
   (Point Sources, Pencil Beams, Detectors, Time Snapshots) shown with the
   advanced properties, their labels and column headers read from the Qt
   widgets and that part of the panel saved (solve_tables.png).
3. Plot Over Line downstream of Solve Diffusion, in a line chart view.
4. The crash of issue 20: Linear Solver set to an unknown name, applied, all
   views rendered; the failed output must be empty and the GUI alive.
5. Linear Solver back to "default": the Outgoing Radiance is shown again and
   the render view saved (fixed camera, colour range and size) for the
   baseline comparison.
6. Writes results.json and the marker, then quits the application with exit
   code 0 (1 and error.txt on any exception), through QCoreApplication::exit:
   the GUI's Python has no Qt binding, so it is called with ctypes.
"""

import contextlib
import ctypes
import json
import os
import subprocess
import time
import traceback

from paraview.simple import *  # noqa: F401,F403
from paraview import servermanager
from vtkmodules.util.numpy_support import vtk_to_numpy

OUT = os.environ["TRANSLUCENCY_GUI_OUT"]
QT = ctypes.CDLL("libQt5Core.so.5")


def process_events():
    """QCoreApplication::processEvents(QEventLoop::AllEvents): let the GUI
    update its panels and views as it would between two user actions."""
    for _ in range(3):
        QT._ZN16QCoreApplication13processEventsE6QFlagsIN10QEventLoop17ProcessEventsFlagEE(0)


def quit_application(code):
    """QCoreApplication::exit(code): the event loop ends after this script."""
    QT._ZN16QCoreApplication4exitEi(code)


@contextlib.contextmanager
def recorded_messages():
    """The text of every VTK warning and error reported inside the block
    (vtkOutputWindow: what the GUI shows in its Output Messages pop-up)."""
    from vtkmodules.util.misc import calldata_type
    from vtkmodules.util.vtkConstants import VTK_STRING
    from vtkmodules.vtkCommonCore import vtkCommand, vtkOutputWindow

    messages = []

    @calldata_type(VTK_STRING)
    def record(caller, event, text):
        messages.append(text or "")

    window = vtkOutputWindow.GetInstance()
    tags = [window.AddObserver(event, record)
            for event in (vtkCommand.WarningEvent, vtkCommand.ErrorEvent)]
    try:
        yield messages
    finally:
        for tag in tags:
            window.RemoveObserver(tag)


def screen_dump(path):
    """The whole X screen (the GUI with its panels) as an xwd file."""
    subprocess.run(["xwd", "-root", "-silent", "-out", path], check=True, timeout=60)


def array_names(attributes):
    return [attributes.GetArrayName(i) for i in range(attributes.GetNumberOfArrays())]


def colouring(display, view, name):
    """What ParaView chose for `display`: array, LUT mode and component,
    and the colour bar's title and component title."""
    lut = GetColorTransferFunction(name)
    bar = GetScalarBar(lut, view)
    return {"array": [str(v) for v in display.ColorArrayName],
            "vector_mode": str(lut.VectorMode).strip("'\""), "vector_component": int(lut.VectorComponent),
            "title": str(bar.Title), "component_title": str(bar.ComponentTitle)}


def default_colouring(solve, radiance, view):
    found = {}
    shown = GetDisplayProperties(radiance, view)
    shown.SetScalarBarVisibility(view, True)  # the colour bar as the toolbar button shows it
    found["radiance"] = colouring(shown, view, "Radiance")
    shown.SetScalarBarVisibility(view, False)
    solved = Show(solve, view)
    ColorBy(solved, ("POINTS", "Fluence"))  # the combo box: the array, its default mode
    solved.SetScalarBarVisibility(view, True)
    Hide(radiance, view)
    view.OrientationAxesVisibility = 0
    view.CameraPosition = [0.0, 14.5, 80.0]
    view.CameraFocalPoint = [0.0, 14.5, 0.0]
    view.CameraViewUp = [0.0, 1.0, 0.0]
    Render(view)
    process_events()
    found["fluence"] = colouring(solved, view, "Fluence")
    SaveScreenshot(os.path.join(OUT, "fluence_colour_bar.png"), view,
                   ImageResolution=[640, 480], TransparentBackground=0)
    solved.SetScalarBarVisibility(view, False)
    Hide(solve, view)
    Show(radiance, view)
    Render(view)
    process_events()
    return found


def linear_solver_choices(solve):
    """The Linear Solver drop-down's names for each Solver chosen in the
    panel (unchecked values: the GUI's decorator must follow them), and the
    value left after choosing quadgraph's "relaxation" then divergence."""
    solver = solve.GetProperty("Solver").SMProperty
    linear = solve.GetProperty("LinearSolver").SMProperty
    domain = solve.GetProperty("LinearSolver").GetDomain("list")
    solvers = solver.FindDomain("vtkSMEnumerationDomain")
    checked = solver.GetElement(0)
    choices = {}
    for i in range(solvers.GetNumberOfEntries()):
        solver.SetUncheckedElement(0, solvers.GetEntryValue(i))
        process_events()
        choices[solvers.GetEntryText(i)] = [
            domain.GetString(k) for k in range(domain.GetNumberOfStrings())]
    solver.SetUncheckedElement(0, solvers.GetEntryValueForText("quadgraph"))
    process_events()
    linear.SetUncheckedElement(0, "relaxation")
    solver.SetUncheckedElement(0, solvers.GetEntryValueForText("divergence"))
    process_events()
    choices["value_after_switch"] = str(linear.GetUncheckedElement(0))
    solve.UpdatePropertyInformation()
    table = [str(v) for v in solve.GetProperty("LinearSolverTable")]
    choices["table"] = [list(pair) for pair in zip(table[0::2], table[1::2])]
    solver.SetUncheckedElement(0, checked)  # back to the applied state
    linear.ClearUncheckedElements()
    process_events()
    return choices


def panel_tables(png):
    """What the Properties panel shows of Solve Diffusion's four tables
    (Plugin/TranslucencyPanelInspector.cxx), with their picture in `png`."""
    plugin = ctypes.CDLL(os.environ["TRANSLUCENCY_PLUGIN"])
    inspect = plugin.TranslucencyInspectPanelTables
    inspect.restype = ctypes.c_char_p
    inspect.argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p]
    process_events()
    text = inspect(b"SolveDiffusion", b"PointSources,PencilBeams,Detectors,TimeSnapshots",
                   png.encode())
    process_events()
    return json.loads(text.decode())


def run():
    results = {"seconds": {}}
    start = time.perf_counter()

    def stage(name):
        results["seconds"][name] = round(time.perf_counter() - start, 2)
    LoadPlugin(os.environ["TRANSLUCENCY_PLUGIN"], remote=False, ns=globals())
    bunny = os.path.join(os.environ["TRANSLUCENCY_SOURCE_DIR"], "Data", "bunny.ply")

    # 1. The chain, step by step as from the Filters > Translucency menu.
    view = GetActiveViewOrCreate("RenderView")
    reader = TranslucencySurfaceReader(FileName=bunny)
    Show(reader, view)
    process_events()
    stage("reader")
    # hxt with uniform sizing re-meshes the surface: 3,000 tets as asked
    # (TetGen keeps the bunny's 3,674 triangles: 45,113 tets at least, and
    # the GUI's 11 checks do not depend on the size).
    tetra = TetrahedralizeSurface(Input=reader, TargetNumberOfTets=3000, Mesher="hxt",
                                  UniformSizing=1)
    assign = AssignScatteringCoefficients(Input=tetra)
    # The scene is set explicitly (not left to the defaults) so that the baseline
    # picture stays valid when a default changes: marble lit from above-front.
    assign.MaterialName = "marble"
    # The collimated model too (Surface: the model the baseline was drawn with;
    # the default by light kind, extended-moments here, draws the scanned
    # surface's bumps into the lit side: DiffuseOptics.md). Its Irradiance is
    # the default model's, every light (1b compares them).
    irradiance = SurfaceIrradiance(Input=assign, DirectionalLights=[0.0, -1.0, -1.0, 1.0],
                                   UniformLightIrradiance=0.1, CollimatedModel=0)
    solve = SolveDiffusion(Input=irradiance)
    radiance = OutgoingRadiance(Input=solve)
    for proxy in (tetra, assign, irradiance, solve, radiance):
        SetActiveSource(proxy)
        Show(proxy, view)
        Render(view)
        process_events()
        stage(proxy.GetXMLLabel())
    for proxy in (reader, tetra, assign, irradiance, solve):
        Hide(proxy, view)

    stage("chain")

    # 1a. The default colouring (issue 33): Outgoing Radiance, shown as the
    # GUI shows it, is coloured by its active scalars Radiance, component G
    # (not the magnitude of R, G, B), with the unit in the colour bar's
    # title; Fluence, chosen in the colour combo box, likewise. The view with
    # the colour bar is saved for Documentation/images.
    results["default_colouring"] = default_colouring(solve, radiance, view)

    # 1b. Surface Irradiance as the menu creates it: the default light must be
    # there (it was dropped: the XML gave default values without a size), the
    # same lights as the explicit ones above, so the same Irradiance exactly.
    default_light = SurfaceIrradiance(Input=assign)
    SetActiveSource(default_light)
    process_events()
    results["default_directional_lights"] = list(default_light.DirectionalLights)
    results["default_uniform"] = default_light.UniformLightIrradiance[0] \
        if hasattr(default_light.UniformLightIrradiance, "__len__") \
        else default_light.UniformLightIrradiance

    def irradiance_values(proxy):
        array = servermanager.Fetch(proxy).GetPointData().GetArray("Irradiance")
        return vtk_to_numpy(array).ravel().tolist()  # one call, not one per value

    explicit_q = irradiance_values(irradiance)
    default_q = irradiance_values(default_light)
    results["default_vs_explicit_max_diff"] = max(
        abs(a - b) for a, b in zip(explicit_q, default_q)) if explicit_q else None
    results["default_points"] = len(default_q) // 3
    description = servermanager.Fetch(default_light).GetFieldData().GetAbstractArray(
        "TranslucencyLightsDescription")
    results["default_description"] = description.GetValue(0) if description else None
    # The interactive light: its line widget in the panel, placed from the
    # bounds (Point 1 above and behind the object, Point 2 at its centre).
    default_light.InteractiveLight = 1
    process_events()
    Render(view)
    process_events()
    results["interactive_point1"] = list(default_light.InteractiveLightPoint1)
    results["interactive_point2"] = list(default_light.InteractiveLightPoint2)
    results["bounds"] = list(servermanager.Fetch(assign).GetBounds())
    with_interactive = irradiance_values(default_light)
    results["interactive_adds_light"] = sum(with_interactive) - sum(default_q)
    description = servermanager.Fetch(default_light).GetFieldData().GetAbstractArray(
        "TranslucencyLightsDescription")
    results["interactive_description"] = description.GetValue(0) if description else None
    Delete(default_light)
    del default_light
    process_events()

    # 2a. Paint Scattering Coefficients from the Translucency menu: its panel
    # has the polyline widget of the stroke with the first stroke from the
    # input's bounds (two handles across the front), created without a VTK
    # warning or error (the pop-up "minimum of 1 points required" of a widget
    # without handles); the render view with and without the widget, and the
    # whole screen (xwd) for Documentation/. Then two handles across the
    # bunny's back, painted along the line between them.
    with recorded_messages() as messages:
        paint = PaintScatteringCoefficients(Input=assign)
        SetActiveSource(paint)
        process_events()
        Show(assign, view)
        Render(view)
        process_events()
    results["paint_creation_messages"] = messages
    results["paint_default_stroke"] = list(paint.StrokePoints)
    view.OrientationAxesVisibility = 0
    view.CameraPosition = [0.0, 14.5, 80.0]
    view.CameraFocalPoint = [0.0, 14.5, 0.0]
    view.CameraViewUp = [0.0, 1.0, 0.0]
    Render(view)
    process_events()
    SaveScreenshot(os.path.join(OUT, "paint_widget_shown.png"), view, ImageResolution=[640, 480],
                   TransparentBackground=0)
    screen_dump(os.path.join(OUT, "paint_gui.xwd"))
    SetActiveSource(assign)  # the widget goes with the panel
    process_events()
    Render(view)
    process_events()
    SaveScreenshot(os.path.join(OUT, "paint_widget_hidden.png"), view, ImageResolution=[640, 480],
                   TransparentBackground=0)
    Hide(assign, view)
    SetActiveSource(paint)
    process_events()
    paint.StrokePoints = [-8.0, 16.0, 3.0, 8.0, 16.0, 3.0]
    paint.Width = 1.5
    Show(paint, view)
    Render(view)
    process_events()
    weights = servermanager.Fetch(paint).GetCellData().GetArray("PaintWeight")
    results["paint_cells_above_half"] = sum(
        1 for i in range(weights.GetNumberOfTuples()) if weights.GetValue(i) > 0.5)
    Hide(paint, view)

    # 2. The Solve Diffusion panel.
    SetActiveSource(solve)
    process_events()
    domain = solve.GetProperty("LinearSolver").GetDomain("list")
    results["linear_solver_choices"] = [
        domain.GetString(i) for i in range(domain.GetNumberOfStrings())]
    # 2b. The Linear Solver drop-down follows the Solver drop-down before
    # Apply (issue 33): each Solver chosen in the panel (its unchecked value,
    # what the combo box sets), the drop-down's domain read back; then a
    # choice the next Solver does not accept goes back to "default".
    results["linear_solver_choices_by_solver"] = linear_solver_choices(solve)
    # 2c. The tables of the panel (issue 33): shown with the advanced
    # properties (the gear button: `--dr` ignores the settings that would
    # turn it on), each with its label and column headers, read from the Qt
    # widgets by the plugin's TranslucencyInspectPanelTables (the GUI's Python
    # has no Qt binding), and a picture of that part of the panel.
    results["panel_tables"] = panel_tables(os.path.join(OUT, "solve_tables.png"))

    stage("panel")

    # 3. Plot Over Line downstream, in a line chart view of its own.
    line = PlotOverLine(Input=solve)
    chart = CreateView("XYChartView")
    AssignViewToLayout(view=chart)
    Show(line, chart)
    Render(chart)
    process_events()
    results["probed_points_before"] = servermanager.Fetch(line).GetNumberOfPoints()
    results["radiance_points_before"] = servermanager.Fetch(radiance).GetNumberOfPoints()

    stage("plot_over_line")

    # 4. An unknown linear solver, applied with Plot Over Line downstream.
    solve.LinearSolver = "nosuchsolver"
    Render(view)
    Render(chart)
    process_events()
    failed = servermanager.Fetch(solve)
    results["failed_output"] = {
        "class": failed.GetClassName(),
        "points": failed.GetNumberOfPoints(),
        "cells": failed.GetNumberOfCells(),
        "has_points_object": failed.GetPoints() is not None,
        "point_arrays": array_names(failed.GetPointData()),
        "cell_arrays": array_names(failed.GetCellData()),
    }
    results["radiance_points_failed"] = servermanager.Fetch(radiance).GetNumberOfPoints()

    stage("failure")

    # 5. Repaired: the picture for the baseline.
    solve.LinearSolver = "default"
    SetActiveSource(radiance)
    display = Show(radiance, view)
    ColorBy(display, ("POINTS", "Radiance", "Magnitude"))
    lut = GetColorTransferFunction("Radiance")
    lut.ApplyPreset("Inferno (matplotlib)", True)
    # W/(mm^2 sr). The default read-out is energy-conserving, eq. 3 / eta^2 (marble:
    # eta 1.3), the bunny about 0.05 to 0.54: on 0..1/eta^2 it draws the same picture
    # as eq. 3 as printed on 0..1, the baseline's (a default without the 1/eta^2
    # would draw it 1.69x brighter and fail the comparison).
    lut.RescaleTransferFunction(0.0, 1.0 / 1.3 ** 2)
    display.SetScalarBarVisibility(view, False)
    display.Ambient = 1.0  # the solver's light only, not the view's
    display.Diffuse = 0.0
    view.OrientationAxesVisibility = 0
    view.UseColorPaletteForBackground = 0
    view.Background = [0.1, 0.1, 0.12]
    view.CameraPosition = [0.0, 14.5, 80.0]  # the bunny: 30 mm, centre (0, 14.5, 0)
    view.CameraFocalPoint = [0.0, 14.5, 0.0]
    view.CameraViewUp = [0.0, 1.0, 0.0]
    view.CameraParallelProjection = 0
    view.CameraViewAngle = 30
    Render(view)
    Render(chart)
    process_events()
    data = servermanager.Fetch(radiance)
    results["radiance_points"] = data.GetNumberOfPoints()
    results["radiance_range"] = list(data.GetPointData().GetArray("Radiance").GetRange(-1))
    # The proxy's read-out, by its enumeration text.
    results["radiance_readout"] = radiance.GetProperty("RadianceReadout").GetElement(0)
    results["probed_points_after"] = servermanager.Fetch(line).GetNumberOfPoints()
    SaveScreenshot(os.path.join(OUT, "render_view.png"), view, ImageResolution=[640, 480],
                   TransparentBackground=0)
    process_events()

    stage("picture")
    with open(os.path.join(OUT, "results.json"), "w") as f:
        json.dump(results, f, indent=1)
    with open(os.path.join(OUT, "marker"), "w") as f:
        f.write("the GUI ran the whole script\n")


try:
    run()
    quit_application(0)
except BaseException:  # report everything and leave: the test must not hang
    with open(os.path.join(OUT, "error.txt"), "w") as f:
        f.write(traceback.format_exc())
    quit_application(1)
