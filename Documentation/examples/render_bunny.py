"""Render the Stanford bunny in marble with the Translucency VTK filters.

How to run (after `make demo` or `make build`), from any directory (the bunny is
found with translucency.find_data; the picture's directory is created):

    export PYTHONPATH=/path/to/translucency/build/lib/python3.11/site-packages
    xvfb-run -a /usr/bin/python3 render_bunny.py [out.png]

(`pvpython` works too.) Without an X display, drop xvfb-run only if you skip
step 7 (pass --no-render). `--target-tets=N` asks for another mesh size than
100,000 (a quick try: --target-tets=5000 gives TetGen's coarsest mesh of
this bunny, about 45,000 tets, and a warning saying why).

The pipeline is made of ordinary VTK classes plus the five Translucency filters:
surface -> tetrahedra -> coefficients -> boundary irradiance -> fluence ->
outgoing radiance -> picture. VTK filters only log their errors;
translucency.update(filter) updates and raises translucency.PipelineError with
the filter's message instead (try SetMaterialName("marbel") in step 3).
"""

import os
import sys

import vtk  # ParaView's VTK 9.2 (python3-paraview)
import translucency

bunny = translucency.find_data("bunny.ply")
out_png = next((a for a in sys.argv[1:] if not a.startswith("--")), "bunny.png")
render = "--no-render" not in sys.argv
target_tets = next((int(a.split("=", 1)[1]) for a in sys.argv[1:]
                    if a.startswith("--target-tets=")), 100000)

# 1. Read the closed triangle surface (lengths in mm).
reader = vtk.vtkPLYReader()
reader.SetFileName(bunny)

# 2. Fill it with about 100k quality tetrahedra (TetGen).
tetra = translucency.vtkTetrahedralizeSurface()
tetra.SetInputConnection(reader.GetOutputPort())
tetra.SetTargetNumberOfTets(target_tets)

# 3. Marble everywhere (a measured preset; or set explicit coefficients in 1/mm).
material = translucency.vtkAssignScatteringCoefficients()
material.SetInputConnection(tetra.GetOutputPort())
material.SetMaterialName("marble")

# 4. Light: a directional key light from above-front plus a weak uniform light.
light = translucency.vtkSurfaceIrradiance()
light.SetInputConnection(material.GetOutputPort())
light.AddDirectionalLight(0.0, -1.0, -1.0, 1.0)  # direction of travel, W/mm^2
light.SetUniformLightIrradiance(0.1)  # W/mm^2

# 5. Solve the diffusion equation (TransCut discrete divergence + CG).
solve = translucency.vtkSolveDiffusion()
solve.SetInputConnection(light.GetOutputPort())
solve.SetRelTol(1e-6)
translucency.update(solve)  # raises translucency.PipelineError on any error upstream
for c, name in enumerate("RGB"):
    print(f"channel {name}: {solve.GetNumberOfIterations(c)} iterations, "
          f"residual {solve.GetFinalResidual(c):.2e}")

# 6. Outgoing radiance on the surface (TransCut eq. 3).
radiance = translucency.vtkOutgoingRadiance()
radiance.SetInputConnection(solve.GetOutputPort())
surface = translucency.update(radiance)
print("surface points:", surface.GetNumberOfPoints(),
      "max radiance R:", surface.GetPointData().GetArray("Radiance").GetRange(0)[1])

# 7. Show it: RadianceRGB is the tone-mapped radiance (exposure x radiance,
# sRGB-encoded; radiance.SetExposure(x) to choose, default automatic), the
# colours the CLI's `render --png` and ParaView (Map Scalars off) show.
if render:
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputData(surface)
    mapper.SetScalarModeToUsePointFieldData()
    mapper.SelectColorArray("RadianceRGB")
    mapper.SetColorModeToDirectScalars()
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().LightingOff()
    ren = vtk.vtkRenderer()
    ren.AddActor(actor)
    ren.SetBackground(0.08, 0.08, 0.1)
    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.AddRenderer(ren)
    win.SetSize(800, 600)
    ren.ResetCamera()
    win.Render()
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(win)
    writer = vtk.vtkPNGWriter()
    writer.SetInputConnection(grab.GetOutputPort())
    if os.path.dirname(out_png):
        os.makedirs(os.path.dirname(out_png), exist_ok=True)
    writer.SetFileName(out_png)
    writer.Write()
    print("wrote", out_png)
