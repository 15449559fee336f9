"""Relight of the issue-31 chain where the user meets it: in the ParaView GUI
(the interactive light's line widget moved) or in pvbatch, same chain, same
mesh, same steps.

    # the GUI (under Xvfb), then pvbatch on the same mesh:
    TRANSLUCENCY_PLUGIN=build/lib/paraview-plugins/Translucency/Translucency.so \\
    TRANSLUCENCY_RELIGHT_MESH=bunny1m.vtu TRANSLUCENCY_RELIGHT_OUT=gui.json \\
    OMP_NUM_THREADS=2 xvfb-run -a -s "-screen 0 1280x1024x24" \\
        paraview --dr --script=scripts/relight_gui_timing.py
    TRANSLUCENCY_PLUGIN=... TRANSLUCENCY_RELIGHT_MESH=bunny1m.vtu \\
    TRANSLUCENCY_RELIGHT_OUT=pvbatch.json OMP_NUM_THREADS=2 \\
        pvbatch scripts/relight_gui_timing.py

(scripts/relight_gui_figure.sh runs both and prints the table.)

1. Reads TRANSLUCENCY_RELIGHT_MESH (a tetrahedral .vtu; if it does not exist,
   Data/bunny.ply is tetrahedralised to TRANSLUCENCY_RELIGHT_TETS tets,
   default 1,000,000, and saved there first, never overwritten).
2. Builds XML reader -> Assign (marble) -> Surface Irradiance (no fixed
   directional light, the uniform light 0.1 W/mm^2, the interactive light
   on: a directional light from Point 1 to Point 2 of the line widget, 1
   W/mm^2, along (0, -1, -1)) -> Solve Diffusion (defaults) -> Outgoing
   Radiance, shown in the render view (GUI) or updated (pvbatch): the cold
   chain, timed.
3. Relights TRANSLUCENCY_RELIGHT_STEPS times (default 5): Point 1 moved so
   that the light turns 15 degrees about x, alternately there and back (the
   property the line widget drives); each timed as the user meets it: in the
   GUI from the property change to the rendered view (Outgoing Radiance's
   UpdatePipeline, Render, then the GUI's pending events; each phase's
   median is reported too), in pvbatch to Outgoing Radiance's UpdatePipeline.
4. Writes TRANSLUCENCY_RELIGHT_OUT (JSON): mode, tets, seconds (cold,
   relights, median) and, with
   TRANSLUCENCY_RELIGHT_FIELDS=1, the Fluence of the cold chain and of each
   relight (for the GUI test's comparison with pvbatch; small meshes only).
   In the GUI the application then quits (exit code 0, or 1 with the
   traceback in the JSON's "error").
"""

import json
import math
import os
import statistics
import sys
import time
import traceback

from paraview.simple import *  # noqa: F401,F403
from paraview import servermanager
from vtkmodules.util.numpy_support import vtk_to_numpy

OUT = os.environ["TRANSLUCENCY_RELIGHT_OUT"]
MESH = os.environ["TRANSLUCENCY_RELIGHT_MESH"]
STEPS = int(os.environ.get("TRANSLUCENCY_RELIGHT_STEPS", "5"))
FIELDS = os.environ.get("TRANSLUCENCY_RELIGHT_FIELDS") == "1"
SOURCE_DIR = os.environ.get("TRANSLUCENCY_SOURCE_DIR") or os.path.join(
    os.path.dirname(os.path.abspath(__file__)), "..")


def in_gui():
    """True inside the paraview application (its pqCore library is loaded)."""
    with open("/proc/self/maps") as f:
        return "libpqCore" in f.read()


GUI = in_gui()
if GUI:
    import ctypes
    QT = ctypes.CDLL("libQt5Core.so.5")


def process_events():
    """The GUI's pending events (panels, widgets, views), as between two user actions."""
    if GUI:
        for _ in range(3):
            QT._ZN16QCoreApplication13processEventsE6QFlagsIN10QEventLoop17ProcessEventsFlagEE(0)


def light_point1(centre, distance, degrees):
    """Point 1 of a directional light through `centre` along (0, -1, -1)
    turned by `degrees` about x (the light travels from Point 1 to the centre)."""
    t = math.radians(degrees)
    d = (0.0, -math.cos(t) + math.sin(t), -math.sin(t) - math.cos(t))
    n = math.sqrt(sum(c * c for c in d))
    return [centre[k] - distance * d[k] / n for k in range(3)]


def fluence(proxy):
    array = servermanager.Fetch(proxy).GetPointData().GetArray("Fluence")
    return vtk_to_numpy(array).ravel().tolist()  # one call, not one per value


def run(results):
    LoadPlugin(os.environ["TRANSLUCENCY_PLUGIN"], remote=False, ns=globals())
    if not os.path.exists(MESH):
        surface = TranslucencySurfaceReader(FileName=os.path.join(SOURCE_DIR, "Data", "bunny.ply"))
        tets = TetrahedralizeSurface(
            Input=surface,
            TargetNumberOfTets=int(os.environ.get("TRANSLUCENCY_RELIGHT_TETS", "1000000")))
        SaveData(MESH, proxy=tets)
        Delete(tets)
        Delete(surface)
    reader = XMLUnstructuredGridReader(FileName=[MESH])
    reader.UpdatePipeline()
    bounds = reader.GetDataInformation().GetBounds()
    centre = [0.5 * (bounds[2 * k] + bounds[2 * k + 1]) for k in range(3)]
    distance = math.sqrt(sum((bounds[2 * k + 1] - bounds[2 * k]) ** 2 for k in range(3)))
    results["tets"] = reader.GetDataInformation().GetNumberOfCells()

    assign = AssignScatteringCoefficients(Input=reader, MaterialName="marble")
    light = SurfaceIrradiance(Input=assign, DirectionalLights=[], UniformLightIrradiance=0.1)
    light.InteractiveLight = 1
    light.InteractiveLightPower = 1.0
    light.InteractiveLightPoint2 = centre
    light.InteractiveLightPoint1 = light_point1(centre, distance, 0.0)
    solve = SolveDiffusion(Input=light)
    radiance = OutgoingRadiance(Input=solve)

    view = GetActiveViewOrCreate("RenderView") if GUI else None

    phases = {"pipeline": [], "render": [], "events": []}

    def update():
        if GUI:
            # The parts of what the user waits for: the pipeline (as pvbatch's
            # UpdatePipeline), the render, the GUI's pending events (panels,
            # pipeline browser, data information).
            t0 = time.perf_counter()
            radiance.UpdatePipeline()
            t1 = time.perf_counter()
            Render(view)
            t2 = time.perf_counter()
            process_events()
            t3 = time.perf_counter()
            for name, seconds in zip(phases, (t1 - t0, t2 - t1, t3 - t2)):
                phases[name].append(seconds)
        else:
            radiance.UpdatePipeline()

    if os.environ.get("TRANSLUCENCY_RELIGHT_DIAG") == "1":
        print("cold starts at monotonic %.3f s" % time.monotonic(), flush=True)
    start = time.perf_counter()
    cold = {}
    if GUI:
        # Show runs the chain (cold); then the picture. Each part timed
        # (cold_phase_seconds): the chain and its representation, the colour
        # map, the panel, then update()'s pipeline, render and events.
        t0 = time.perf_counter()
        display = Show(radiance, view)
        t1 = time.perf_counter()
        ColorBy(display, ("POINTS", "Radiance", "Magnitude"))
        t2 = time.perf_counter()
        SetActiveSource(light)  # its panel, with the line widget shown
        view.ResetCamera()
        t3 = time.perf_counter()
        cold = {"show": t1 - t0, "color_by": t2 - t1, "panel": t3 - t2}
    update()
    results["cold_seconds"] = time.perf_counter() - start
    if os.environ.get("TRANSLUCENCY_RELIGHT_DIAG") == "1":
        print("cold ended at monotonic %.3f s" % time.monotonic(), flush=True)
    if GUI:
        cold.update({name: v[0] for name, v in phases.items()})
        results["cold_phase_seconds"] = cold
    if FIELDS:
        results["fluence"] = [fluence(solve)]
    relights = []
    diagnose = os.environ.get("TRANSLUCENCY_RELIGHT_DIAG") == "1"
    for k in range(STEPS):
        degrees = 15.0 if k % 2 == 0 else 0.0
        start = time.perf_counter()
        light.InteractiveLightPoint1 = light_point1(centre, distance, degrees)  # the widget's drag
        update()
        relights.append(time.perf_counter() - start)
        if diagnose:
            # What ParaView's data information of each proxy costs after a
            # relight (the GUI's panels and pipeline browser gather it).
            for name, proxy in (("light", light), ("solve", solve), ("radiance", radiance)):
                t0 = time.perf_counter()
                proxy.GetDataInformation().GetNumberOfCells()
                print("  data information of %s: %.3f s" % (name, time.perf_counter() - t0),
                      flush=True)
        if FIELDS:
            results["fluence"].append(fluence(solve))
        print("relight %d: %.3f s" % (k + 1, relights[-1]), flush=True)
    results["relight_seconds"] = relights
    if GUI:
        # Medians of the relights' phases (the first entry is the cold chain's).
        results["relight_phase_median_seconds"] = {
            name: statistics.median(v[1:]) for name, v in phases.items() if len(v) > 1}
    results["relight_median_seconds"] = statistics.median(relights)


def main():
    results = {"mode": "gui" if GUI else "pvbatch",
               "threads": os.environ.get("OMP_NUM_THREADS", "")}
    code = 0
    try:
        run(results)
    except BaseException:  # report everything and leave: a test must not hang
        results["error"] = traceback.format_exc()
        code = 1
    with open(OUT, "w") as f:
        json.dump(results, f)
    if GUI:
        QT._ZN16QCoreApplication4exitEi(code)
    elif code:
        sys.exit(results["error"])


main()
