"""Diffuse optics in ParaView: a point source inside a slab, two detectors on
its surface and the Detector Readings tables, as a pipeline state for
pvpython / pvbatch (or the Python shell of the ParaView GUI).

How to run, from the repository root after `make build` (no X display needed
without --chart):

    pvpython --force-offscreen-rendering Documentation/examples/detectors_paraview.py \
        build/lib/paraview-plugins/Translucency/Translucency.so [OUTPUT_DIR] [--chart]

1. Load the plugin; build Box (40 x 40 x 15 mm) -> Triangulate ->
   Tetrahedralize Surface -> Assign Scattering Coefficients (mu_a 0.01 /mm,
   mu_s' 1 /mm, eta 1.4) -> Surface Irradiance with no light (the source
   alone). Each filter is updated before the next is made, as Apply does in
   the GUI, so the widgets of the next start from the data bounds.
2. Solve Diffusion with its Interactive Point Source on (in the GUI: tick
   "Interactive Point Source" and drag the handle): 1 W, 5 mm below the
   centre of the top face. Two detectors on the top face, 10 and 15 mm from
   the point above the source (Detectors: x, y, z, fibre radius in mm).
3. Detector Readings: port 0 has one row per detector (requested and surface
   position, radius, fluence and exitance R, G, B in W/mm^2); it is printed
   and saved as OUTPUT_DIR/detectors.csv (default: the current directory).
4. The same with 20 time gates over 0..2 ns: port 1 ("Time Gates") has the
   column "Time (ns)" and the detectors' temporal point-spread functions,
   saved as OUTPUT_DIR/tpsf.csv. In the GUI: select port 1, open a Line
   Chart View, X Array Name "Time (ns)", tick Detector0_FluenceR and
   Detector1_FluenceR. With --chart this script renders that chart to
   OUTPUT_DIR/tpsf.png (a chart view needs an X display: run under xvfb-run).
Documentation/DiffuseOptics.md has the model and the units.
"""

import os
import sys

from paraview.simple import *  # noqa: F401,F403
from paraview import servermanager

args = [a for a in sys.argv[1:] if not a.startswith("--")]
plugin = args[0]
out_dir = args[1] if len(args) > 1 else "."
os.makedirs(out_dir, exist_ok=True)
LoadPlugin(plugin, ns=globals())

# 1. The slab: top face at z = 7.5 mm.
box = Box(XLength=40.0, YLength=40.0, ZLength=15.0)
tets = TetrahedralizeSurface(Input=Triangulate(Input=box), TargetNumberOfTets=8000)
tissue = AssignScatteringCoefficients(
    Input=tets, MaterialName="", AbsorptionCoefficient=[0.01, 0.01, 0.01],
    ReducedScatteringCoefficient=[1.0, 1.0, 1.0], RefractiveIndex=1.4)
dark = SurfaceIrradiance(Input=tissue, DirectionalLights=[], UniformLightIrradiance=0.0,
                         DefaultLights=0)
dark.UpdatePipeline()

# 2. The source (the handle widget's property) and two detectors.
solve = SolveDiffusion(Input=dark, Solver="divergence", RelTol=1e-8)
solve.InteractivePointSource = 1
solve.InteractivePointSourcePosition = [0.0, 0.0, 2.5]  # 5 mm below the top face
solve.InteractivePointSourcePower = [1.0, 1.0, 1.0]     # W per channel
solve.Detectors = [10.0, 0.0, 7.5, 1.0,   # x, y, z (mm), fibre radius (mm)
                   15.0, 0.0, 7.5, 1.0]

# 3. The detector table.
readings = DetectorReadings(Input=solve)
readings.UpdatePipeline()
table = servermanager.Fetch(readings, idx=0)
fluence = table.GetColumnByName("FluenceR")
exitance = table.GetColumnByName("ExitanceR")
for k in range(table.GetNumberOfRows()):
    x = table.GetColumnByName("SurfaceX").GetValue(k)
    print("detector %d at x = %.2f mm: fluence %.4e W/mm^2, exitance %.4e W/mm^2 (per W)"
          % (k, x, fluence.GetValue(k), exitance.GetValue(k)))
csv = os.path.join(out_dir, "detectors.csv")
SaveData(csv, proxy=OutputPort(readings, 0))
print("wrote %s" % csv)

# 4. Time-resolved: the TPSF table on port 1.
solve.TimeGates = [0.0, 2.0, 20]   # T0, T1 (ns), number of gates
readings.UpdatePipeline()
tpsf = servermanager.Fetch(readings, idx=1)
time = tpsf.GetColumnByName("Time (ns)")
near = tpsf.GetColumnByName("Detector0_FluenceR")
peak = max(range(tpsf.GetNumberOfRows()), key=near.GetValue)
print("time gates: %d; detector 0's TPSF peaks at %.2f ns" % (tpsf.GetNumberOfRows(),
                                                              time.GetValue(peak)))
tpsf_csv = os.path.join(out_dir, "tpsf.csv")
SaveData(tpsf_csv, proxy=OutputPort(readings, 1))
print("wrote %s" % tpsf_csv)

if "--chart" in sys.argv:
    chart = CreateView("XYChartView")
    display = Show(OutputPort(readings, 1), chart)
    display.UseIndexForXAxis = 0
    display.XArrayName = "Time (ns)"
    display.SeriesVisibility = ["Detector0_FluenceR", "Detector1_FluenceR"]
    chart.LeftAxisLogScale = 1
    chart.LeftAxisTitle = "fluence (J/(mm^2 ns))"
    chart.BottomAxisTitle = "time (ns)"
    png = os.path.join(out_dir, "tpsf.png")
    SaveScreenshot(png, chart, ImageResolution=[800, 500])
    print("wrote %s" % png)
