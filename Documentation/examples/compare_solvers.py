"""Compare the Translucency solvers on one problem, from Python.

How to run (after `make build`), from the repository root:

    export PYTHONPATH=$PWD/build/lib/python3.11/site-packages
    /usr/bin/python3 Documentation/examples/compare_solvers.py [solver ...]

(`pvpython` works too; no X display is needed.) Default solvers: divergence
fem quadgraph grid; add montecarlo for the ground truth (slow). The command
line does the same with pictures: `translucency compare --help`.

1. Build a lit tet mesh once (the solvers share the mesh, the material and q).
2. Run vtkSolveDiffusion once per solver (SetSolverByName). Errors stop the
   script with the filter's message: an unknown solver name (try `femm`) in
   translucency.raise_on_error(), a failing filter in translucency.update(),
   both raise translucency.PipelineError.
3. Compare boundary fluence against the FEM reference: max and RMS relative error.
"""

import sys

import numpy as np
import vtk
import translucency
from vtkmodules.util.numpy_support import vtk_to_numpy

solvers = sys.argv[1:] or ["divergence", "fem", "quadgraph", "grid"]
reference = "fem"

# 1. A marble sphere of radius 10 mm lit from above, about 20k tets.
sphere = vtk.vtkSphereSource()
sphere.SetRadius(10.0)
sphere.SetThetaResolution(32)
sphere.SetPhiResolution(32)
triangles = vtk.vtkTriangleFilter()
triangles.SetInputConnection(sphere.GetOutputPort())
tetra = translucency.vtkTetrahedralizeSurface()
tetra.SetInputConnection(triangles.GetOutputPort())
tetra.SetTargetNumberOfTets(20000)
material = translucency.vtkAssignScatteringCoefficients()
material.SetInputConnection(tetra.GetOutputPort())
material.SetMaterialName("marble")
light = translucency.vtkSurfaceIrradiance()
light.SetInputConnection(material.GetOutputPort())
light.AddDirectionalLight(0.0, -1.0, 0.0, 1.0)
lit = translucency.update(light)  # raises translucency.PipelineError on any error
print("mesh: %d points, %d tets" % (lit.GetNumberOfPoints(), lit.GetNumberOfCells()))

# 2. One solve per solver (the reference first).
surface_ids = None
fluence = {}
for name in [reference] + [s for s in solvers if s != reference]:
    solve = translucency.vtkSolveDiffusion()
    with translucency.raise_on_error():  # an unknown name raises PipelineError
        solve.SetSolverByName(name)
    solve.SetInputData(lit)
    solve.SetRelTol(1e-8)
    solve.SetNumberOfPhotons(200000)
    phi = vtk_to_numpy(translucency.update(solve).GetPointData().GetArray("Fluence"))
    if surface_ids is None:
        radiance = translucency.vtkOutgoingRadiance()
        radiance.SetInputData(solve.GetOutput())
        surface_ids = vtk_to_numpy(
            translucency.update(radiance).GetPointData().GetArray("vtkOriginalPointIds"))
    fluence[name] = phi[surface_ids]
    print("%-10s %8d unknowns %9d nonzeros  setup %7.1f ms  solve %8.1f ms  iterations %s"
          % (name, solve.GetNumberOfUnknowns(), solve.GetNumberOfNonZeros(),
             solve.GetAssemblyTime(), solve.GetSolveTime(),
             [solve.GetNumberOfIterations(c) for c in range(3)]))

# 3. Relative boundary-fluence error against the reference (floor: 1 % of the
#    channel's maximum, as `translucency compare` does).
ref = fluence[reference]
floor = 0.01 * np.abs(ref).max(axis=0)
for name, phi in fluence.items():
    error = np.abs(phi - ref) / np.maximum(np.abs(ref), floor)
    print("%-10s boundary fluence vs %s: max %.2f %%, RMS %.2f %%"
          % (name, reference, 100 * error.max(), 100 * np.sqrt(np.mean(error ** 2))))
