"""Translucent radiosity in a Cornell box, with the VTK filters from Python.

How to run (after `make build`), from the repository root:

    export PYTHONPATH=$PWD/build/lib/python3.11/site-packages
    xvfb-run -a /usr/bin/python3 Documentation/examples/cornell_box.py [out.png]

(Pass --no-render to skip the picture and the need for X.) The command line
does the same from a scene file, with the paper's four-panel figure:

    xvfb-run -a build/bin/translucency radiosity --scene Data/cornell_box.json \\
        --output out/cornell --png out/cornell_fig6.png

The scene: a box open towards the camera (red wall at x = 0, green wall at
x = L), an opaque yellow block and a tall marble block, lit by a point light
under the ceiling. Light bounces between the walls (form factors F) and
scatters inside the marble (operator S, here by our diffusion solve):
B = (I - S F)^-1 S E.
"""

import os
import sys

import numpy as np
import vtk  # ParaView's VTK 9.2 (python3-paraview)
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy

import translucency

out_png = next((a for a in sys.argv[1:] if not a.startswith("--")), "cornell_box.png")
render = "--no-render" not in sys.argv
L = 55.5  # box side (mm)


def box(lo, hi, level, inward):
    """A closed box surface of triangles; normals inward for the room."""
    source = vtk.vtkTessellatedBoxSource()
    source.SetBounds(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2])
    source.SetLevel(level)
    source.QuadsOff()
    clean = vtk.vtkCleanPolyData()
    clean.SetInputConnection(source.GetOutputPort())
    last = vtk.vtkTriangleFilter()
    last.SetInputConnection(clean.GetOutputPort())
    if inward:
        reverse = vtk.vtkReverseSense()
        reverse.SetInputConnection(last.GetOutputPort())
        reverse.ReverseCellsOn()
        last = reverse
    last.Update()
    out = vtk.vtkPolyData()
    out.DeepCopy(last.GetOutput())
    return out


def with_albedo(poly, colour_of):
    """Add the cell array Albedo (RGB in [0, 1]) from each triangle's centre."""
    centres = vtk.vtkCellCenters()
    centres.SetInputData(poly)
    centres.Update()
    xyz = vtk_to_numpy(centres.GetOutput().GetPoints().GetData())
    albedo = numpy_to_vtk(np.array([colour_of(x) for x in xyz], dtype=float), deep=True)
    albedo.SetName("Albedo")
    poly.GetCellData().AddArray(albedo)
    return poly


# 1. The room: an inward box; drop its front face (y = 0) to open it.
room = box((0, 0, 0), (L, L, L), 12, inward=True)
front = vtk.vtkCellCenters()
front.SetInputData(room)
front.Update()
keep = vtk.vtkIdTypeArray()
for c, x in enumerate(vtk_to_numpy(front.GetOutput().GetPoints().GetData())):
    if x[1] > 1e-6:
        keep.InsertNextValue(c)
selection_node = vtk.vtkSelectionNode()
selection_node.SetFieldType(vtk.vtkSelectionNode.CELL)
selection_node.SetContentType(vtk.vtkSelectionNode.INDICES)
selection_node.SetSelectionList(keep)
selection = vtk.vtkSelection()
selection.AddNode(selection_node)
extract = vtk.vtkExtractSelection()
extract.SetInputData(0, room)
extract.SetInputData(1, selection)
surface = vtk.vtkDataSetSurfaceFilter()
surface.SetInputConnection(extract.GetOutputPort())
surface.Update()
room = surface.GetOutput()


def wall_colour(x):
    if x[0] < 1e-6:
        return (0.63, 0.065, 0.05)  # red
    if x[0] > L - 1e-6:
        return (0.14, 0.45, 0.091)  # green
    return (0.73, 0.73, 0.73)


with_albedo(room, wall_colour)

# 2. The short opaque block (yellow).
block = with_albedo(box((31, 9, 0.05), (47.5, 25.5, 16.5), 4, inward=False),
                    lambda x: (0.8, 0.7, 0.25))

# 3. The tall marble block: tetrahedralise its surface (TetGen) and give it the
#    measured marble coefficients (1/mm).
tetra = translucency.vtkTetrahedralizeSurface()
tetra.SetInputData(box((9, 27, 0.05), (25.5, 43.5, 33), 5, inward=False))
tetra.SetMaxTetVolume(3.0)
marble = translucency.vtkAssignScatteringCoefficients()
marble.SetInputConnection(tetra.GetOutputPort())
marble.SetMaterialName("marble")
marble.Update()

# 4. The scene: one partitioned data set per object.
scene = vtk.vtkPartitionedDataSetCollection()
for index, (name, data) in enumerate(
        [("room", room), ("short block", block), ("marble", marble.GetOutput())]):
    scene.SetPartition(index, 0, data)
    scene.GetMetaData(index).Set(vtk.vtkCompositeDataSet.NAME(), name)

# 5. Translucent radiosity: a point light under the ceiling (W/sr per channel).
radiosity = translucency.vtkTranslucentRadiosity()
radiosity.SetInputData(scene)
radiosity.AddPointLight(L / 2, L / 2, L - 2.5, 2000, 2000, 2000)
radiosity.SetRaysPerPatch(512)
radiosity.SetSubsurfaceMethod(radiosity.SUBSURFACE_DIFFUSION)  # or SUBSURFACE_PROFILE
radiosity.Update()
print("%d patches, %d iterations, form factors %.0f ms (%.1f MiB), iteration %.0f ms"
      % (radiosity.GetNumberOfPatches(), radiosity.GetNumberOfIterations(),
         radiosity.GetFormFactorTime(), radiosity.GetFormFactorMemory() / 2**20,
         radiosity.GetSolveTime()))

# 6. Colour bleeding on the marble: its side facing the red wall is redder than
#    its side facing the green wall, and only through inter-reflection.
output = radiosity.GetOutputDataObject(0)
marble_patches = output.GetPartition(2, 0)
normals = vtk.vtkPolyDataNormals()
normals.SetInputData(marble_patches)
normals.ComputeCellNormalsOn()
normals.ComputePointNormalsOff()
normals.SplittingOff()
normals.ConsistencyOff()
normals.AutoOrientNormalsOff()
normals.Update()
n = vtk_to_numpy(normals.GetOutput().GetCellData().GetArray("Normals"))
b = vtk_to_numpy(marble_patches.GetCellData().GetArray("Radiosity"))
for label, side in (("red", n[:, 0] < -0.9), ("green", n[:, 0] > 0.9)):
    print("marble side facing the %s wall: R/G = %.3f" % (label, b[side, 0].sum() / b[side, 1].sum()))

# 7. A picture of the combined radiosity (cell colours, exposure by hand).
if render:
    renderer = vtk.vtkRenderer()
    peak = np.percentile(np.concatenate(
        [vtk_to_numpy(output.GetPartition(k, 0).GetCellData().GetArray("Radiosity")).max(axis=1)
         for k in range(3)]), 99)
    for k in range(3):
        patches = output.GetPartition(k, 0)
        rgb = vtk_to_numpy(patches.GetCellData().GetArray("Radiosity")) * (0.9 / peak)
        rgb = np.clip(rgb, 0, 1) ** (1 / 2.2) * 255
        colours = numpy_to_vtk(rgb.astype(np.uint8), deep=True)
        colours.SetName("RGB")
        patches.GetCellData().AddArray(colours)
        mapper = vtk.vtkPolyDataMapper()
        mapper.SetInputData(patches)
        mapper.SetScalarModeToUseCellFieldData()
        mapper.SelectColorArray("RGB")
        mapper.SetColorModeToDirectScalars()
        actor = vtk.vtkActor()
        actor.SetMapper(mapper)
        actor.GetProperty().LightingOff()  # the radiosity is the appearance
        renderer.AddActor(actor)
    camera = renderer.GetActiveCamera()
    camera.SetPosition(L / 2, -75, L / 2)
    camera.SetFocalPoint(L / 2, L / 2, L / 2)
    camera.SetViewUp(0, 0, 1)
    camera.SetViewAngle(32)
    renderer.ResetCameraClippingRange()
    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.AddRenderer(renderer)
    window.SetSize(500, 500)
    window.Render()
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(window)
    writer = vtk.vtkPNGWriter()
    writer.SetFileName(out_png)
    writer.SetInputConnection(grab.GetOutputPort())
    writer.Write()
    print("wrote %s" % os.path.abspath(out_png))
