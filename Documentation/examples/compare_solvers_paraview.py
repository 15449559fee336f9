"""Compare two solvers in ParaView: a pipeline state for pvpython / pvbatch
(or the Python shell of the ParaView GUI).

How to run, from the repository root after `make build`:

    pvpython Documentation/examples/compare_solvers_paraview.py \
        build/lib/paraview-plugins/Translucency/Translucency.so [solver]

1. Load the plugin; build Sphere -> Triangulate -> Tetrahedralize Surface ->
   Assign Scattering Coefficients -> Surface Irradiance.
2. Branch into two Solve Diffusion filters: the FEM reference and the solver
   to compare (default: the TransCut discrete divergence). The Solver
   property takes the core's names (divergence, fem, quadgraph, grid,
   montecarlo, as the CLI's --solver); in the GUI it is the "Solver" drop-down.
3. Append the second solver's Fluence to the first (Append Attributes) and
   compute the relative difference with a Python Calculator; print its range.
   In the GUI, colour the result by "RelativeDifference".
"""

import sys

from paraview.simple import *  # noqa: F401,F403

plugin = sys.argv[1]
other = sys.argv[2] if len(sys.argv) > 2 else "divergence"
LoadPlugin(plugin, ns=globals())

# 1.
sphere = Sphere(Radius=10.0, ThetaResolution=32, PhiResolution=32)
tets = TetrahedralizeSurface(Input=Triangulate(Input=sphere), TargetNumberOfTets=20000)
marble = AssignScatteringCoefficients(Input=tets, MaterialName="marble")
lit = SurfaceIrradiance(Input=marble, DirectionalLights=[0.0, -1.0, 0.0, 1.0],
                        UniformLightIrradiance=0.0)

# 2.
reference = SolveDiffusion(Input=lit, Solver="fem", RelTol=1e-8)
compared = SolveDiffusion(Input=lit, Solver=other, RelTol=1e-8, NumberOfPhotons=200000)

# 3.
renamed = PassArrays(Input=compared, PointDataArrays=["Fluence"])
both = AppendAttributes(Input=[reference, PythonCalculator(
    Input=renamed, Expression="inputs[0].PointData['Fluence']", ArrayName="FluenceCompared")])
difference = PythonCalculator(
    Input=both, ArrayName="RelativeDifference",
    Expression="abs(inputs[0].PointData['FluenceCompared'] - inputs[0].PointData['Fluence'])"
               " / max(inputs[0].PointData['Fluence'])")
difference.UpdatePipeline()
low, high = difference.PointData["RelativeDifference"].GetRange(0)
print("%s vs fem: relative fluence difference (red channel) in [%.3g, %.3g]"
      % (other, low, high))
