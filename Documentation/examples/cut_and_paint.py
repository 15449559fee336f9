"""Cut the marble bunny open with a stroke, paint a ketchup vein on the cut, re-solve.

How to run (after `make demo` or `make build`), from any directory:

    export PYTHONPATH=/path/to/translucency/build/lib/python3.11/site-packages
    xvfb-run -a /usr/bin/python3 cut_and_paint.py [PREFIX]

It writes PREFIX_before.png (the whole bunny) and PREFIX_after.png (cut open,
with the vein), both seen from the side the cut removes; PREFIX defaults to
"cut_and_paint". Add --no-render to skip the pictures (no X display needed).

The editing interactions of TransCut (Sec. 5): vtkStrokeCut removes the part of
the tet mesh on one side of a stroke swept along the view direction and relaxes
the cross-section; vtkPaintScatteringCoefficients blends new coefficients into
the tets near a 3D stroke. After either edit the irradiance and the fluence are
recomputed on the edited mesh.
"""

import os
import sys

import numpy as np
import vtk  # ParaView's VTK 9.2 (python3-paraview)
from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy
import translucency

bunny = translucency.find_data("bunny.ply")  # from any directory
prefix = next((a for a in sys.argv[1:] if not a.startswith("--")), "cut_and_paint")
if os.path.dirname(prefix):
    os.makedirs(os.path.dirname(prefix), exist_ok=True)
render = "--no-render" not in sys.argv


def light_and_solve(grid):
    """Irradiance from the same lights, then the fluence and the outgoing radiance."""
    light = translucency.vtkSurfaceIrradiance()
    light.SetInputData(grid)
    light.AddDirectionalLight(1.0, -0.5, -0.5, 1.0)  # travels toward +x: lights the cut face
    light.SetUniformLightIrradiance(0.1)  # W/mm^2
    solve = translucency.vtkSolveDiffusion()
    solve.SetInputConnection(light.GetOutputPort())
    solve.SetRelTol(1e-6)
    radiance = translucency.vtkOutgoingRadiance()
    radiance.SetInputConnection(solve.GetOutputPort())
    radiance.Update()
    print(f"  {grid.GetNumberOfCells()} tets, CG iterations (R, G, B): "
          + ", ".join(str(solve.GetNumberOfIterations(c)) for c in range(3)))
    return radiance.GetOutput()


# 1. Read the closed triangle surface (mm) and fill it with about 60k tetrahedra.
reader = vtk.vtkPLYReader()
reader.SetFileName(bunny)
tetra = translucency.vtkTetrahedralizeSurface()
tetra.SetInputConnection(reader.GetOutputPort())
tetra.SetTargetNumberOfTets(60000)

# 2. Marble everywhere.
material = translucency.vtkAssignScatteringCoefficients()
material.SetInputConnection(tetra.GetOutputPort())
material.SetMaterialName("marble")
material.Update()
marble = material.GetOutput()
(x0, x1, y0, y1, z0, z1) = marble.GetBounds()
cx, cy, cz = 0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.5 * (z0 + z1)

# 3. Before: light and solve the whole bunny.
print("before:")
before = light_and_solve(marble)

# 4. Cut: a 2-point stroke drawn bottom to top through the middle, seen along
#    (0, 0, -1) (looking down -z, +x to the right). Swept along the view, it is
#    the plane x = cx; the filter removes the left of the stroke, x < cx.
stroke_points = vtk.vtkPoints()
stroke_points.InsertNextPoint(cx, y0 - 1.0, z1 + 1.0)
stroke_points.InsertNextPoint(cx, y1 + 1.0, z1 + 1.0)
line = vtk.vtkPolyLine()
line.GetPointIds().SetNumberOfIds(2)
line.GetPointIds().SetId(0, 0)
line.GetPointIds().SetId(1, 1)
lines = vtk.vtkCellArray()
lines.InsertNextCell(line)
stroke = vtk.vtkPolyData()
stroke.SetPoints(stroke_points)
stroke.SetLines(lines)
cut = translucency.vtkStrokeCut()
cut.SetInputData(marble)
cut.SetStrokeData(stroke)
cut.SetViewDirection(0.0, 0.0, -1.0)
cut.Update()
print(f"cut: kept {cut.GetOutput().GetNumberOfCells()} of {marble.GetNumberOfCells()} tets, "
      f"moved {cut.GetNumberOfMovedVertices()} vertices onto the cross-section "
      f"({cut.GetCutTime():.0f} ms)")

# 5. Paint a vein across the cross-section: ketchup-like coefficients (1/mm),
#    mode SET, along a diagonal of stroke points on the plane x = cx.
paint = translucency.vtkPaintScatteringCoefficients()
paint.SetInputConnection(cut.GetOutputPort())
for t in np.linspace(0.0, 1.0, 40):
    paint.AddStrokePoint(cx, y0 + (0.25 + 0.5 * t) * (y1 - y0), z0 + (0.3 + 0.4 * t) * (z1 - z0))
paint.SetWidth(0.03 * (y1 - y0))  # mm
paint.SetModeToSet()
paint.SetTargetAbsorptionCoefficient(0.061, 0.97, 1.45)
paint.SetTargetReducedScatteringCoefficient(0.18, 0.07, 0.03)
paint.Update()
weights = vtk_to_numpy(paint.GetOutput().GetCellData().GetArray("PaintWeight"))
print(f"paint: {int(np.sum(weights > 1e-6))} tets touched")

# 6. After: light and solve the cut, painted mesh.
print("after:")
after = light_and_solve(paint.GetOutput())


# 7. Show both from the removed side (looking along +x), with the exposure of
#    the uncut bunny: tone-map the linear radiance with an sRGB curve. One
#    render window serves both pictures: a window per picture opens and closes
#    an X connection each time, and a connection made while the X server resets
#    after the last client left is dropped (VTK then aborts the program).
window = None


def write_png(surface, path, exposure):
    global window
    values = exposure * vtk_to_numpy(surface.GetPointData().GetArray("Radiance"))
    v = np.clip(values, 0.0, 1.0)
    v = np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055)
    rgb = numpy_to_vtk(np.round(255 * v).astype(np.uint8), deep=1)
    rgb.SetName("RadianceRGB")
    surface.GetPointData().AddArray(rgb)
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
    camera = ren.GetActiveCamera()
    camera.SetFocalPoint(cx, cy, cz)
    camera.SetPosition(cx - 4.0 * (x1 - x0), cy, cz)
    camera.SetViewUp(0.0, 1.0, 0.0)
    ren.ResetCamera(marble.GetBounds())
    if window is None:
        window = vtk.vtkRenderWindow()
        window.SetOffScreenRendering(1)
        window.SetSize(800, 600)
    win = window
    win.GetRenderers().RemoveAllItems()
    win.AddRenderer(ren)
    win.Render()
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(win)
    writer = vtk.vtkPNGWriter()
    writer.SetInputConnection(grab.GetOutputPort())
    writer.SetFileName(path)
    writer.Write()


if render:
    peak = vtk_to_numpy(before.GetPointData().GetArray("Radiance")).max()
    exposure = 0.9 / peak if peak > 0 else 1.0
    write_png(before, prefix + "_before.png", exposure)
    write_png(after, prefix + "_after.png", exposure)
    print("wrote", prefix + "_before.png", "and", prefix + "_after.png")
