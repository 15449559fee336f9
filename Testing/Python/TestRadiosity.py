#!/usr/bin/env python3
"""Tests of vtkTranslucentRadiosity and `translucency radiosity`.

How to run (from a build tree; ctest sets the variables itself):

    PYTHONPATH=<build>/lib/python3.11/site-packages \
    TRANSLUCENCY_CLI=<build>/bin/translucency /usr/bin/python3 TestRadiosity.py

1. A small Cornell-like scene built from VTK sources (an inward box with a
   red wall at x = 0 and a green wall at x = L, an outward marble cube
   tetrahedralised with TetGen), as a vtkPartitionedDataSetCollection and as
   a vtkMultiBlockDataSet: the output has the same structure, every leaf is a
   vtkPolyData of patches with the five radiosity arrays, and
   Radiosity = SubsurfaceRadiosity + InterReflectionRadiosity.
2. Colour bleeding: the marble face towards the red wall is redder (R/G) than
   the face towards the green wall, and only through inter-reflection (the
   first bounce, with a white light, is grey).
3. Relighting keeps the form factors (GetFormFactorTime() == 0).
4. Bad input: albedo > 1, a tet mesh without coefficients, a light inside an
   opaque block -> an error naming the problem.
5. The command line: a scene naming a missing mesh file fails with exit code
   1 and names the file; a tiny scene runs and writes its .vtp files and JSON.
"""

import functools
import sys
import json
import os
import subprocess
import tempfile
import unittest

import numpy as np

import translucency
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonDataModel import (vtkCompositeDataSet, vtkMultiBlockDataSet,
                                           vtkPartitionedDataSetCollection, vtkPolyData)
from vtkmodules.vtkFiltersCore import vtkCleanPolyData, vtkReverseSense, vtkTriangleFilter
from vtkmodules.vtkFiltersSources import vtkCubeSource, vtkTessellatedBoxSource

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import vtk_chain  # noqa: E402

# The executive's "returned failure" error counts among the errors.
Messages = functools.partial(vtk_chain.Messages, executive="errors")

L = 20.0


def box_surface(lo, hi, level, inward):
    box = vtkTessellatedBoxSource()
    box.SetBounds(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2])
    box.SetLevel(level)
    box.QuadsOff()
    clean = vtkCleanPolyData()
    clean.SetInputConnection(box.GetOutputPort())
    tri = vtkTriangleFilter()
    tri.SetInputConnection(clean.GetOutputPort())
    last = tri
    if inward:
        rev = vtkReverseSense()
        rev.SetInputConnection(tri.GetOutputPort())
        rev.ReverseCellsOn()
        last = rev
    last.Update()
    poly = vtkPolyData()
    poly.DeepCopy(last.GetOutput())
    return poly


def add_albedo(poly, colour_of_centroid):
    centres = []
    pts = vtk_to_numpy(poly.GetPoints().GetData())
    for c in range(poly.GetNumberOfCells()):
        ids = [poly.GetCell(c).GetPointId(k) for k in range(3)]
        centres.append(pts[ids].mean(axis=0))
    albedo = np.array([colour_of_centroid(x) for x in centres], dtype=float)
    array = numpy_to_vtk(albedo, deep=True)
    array.SetName("Albedo")
    poly.GetCellData().AddArray(array)
    return albedo


def room_colour(x):
    if x[0] < 1e-6:
        return (0.7, 0.1, 0.1)
    if x[0] > L - 1e-6:
        return (0.1, 0.7, 0.1)
    return (0.7, 0.7, 0.7)


def marble_cube(with_coefficients=True):
    surface = box_surface((7, 7, 0.5), (13, 13, 6.5), 3, False)
    tetra = translucency.vtkTetrahedralizeSurface()
    tetra.SetInputData(surface)
    tetra.SetMaxTetVolume(1.0)
    tetra.Update()
    if not with_coefficients:
        return tetra.GetOutput()
    assign = translucency.vtkAssignScatteringCoefficients()
    assign.SetInputConnection(tetra.GetOutputPort())
    assign.SetMaterialName("marble")
    assign.SetScaleFactor(0.2)  # more translucent than marble at this size
    assign.Update()
    return assign.GetOutput()


def make_collection(room, cube):
    pdc = vtkPartitionedDataSetCollection()
    pdc.SetPartition(0, 0, room)
    pdc.GetMetaData(0).Set(vtkCompositeDataSet.NAME(), "room")
    pdc.SetPartition(1, 0, cube)
    pdc.GetMetaData(1).Set(vtkCompositeDataSet.NAME(), "marble")
    return pdc


def radiosity_filter(data):
    f = translucency.vtkTranslucentRadiosity()
    f.SetInputData(data)
    f.AddPointLight(L / 2, L / 2, L - 1, 400, 400, 400)
    f.SetRaysPerPatch(256)
    return f


def leaves(output):
    it = output.NewIterator()
    it.InitTraversal()
    out = []
    while not it.IsDoneWithTraversal():
        out.append(it.GetCurrentDataObject())
        it.GoToNextItem()
    return out


def cell_array(poly, name):
    return vtk_to_numpy(poly.GetCellData().GetArray(name))


def face_normals(poly):
    pts = vtk_to_numpy(poly.GetPoints().GetData())
    normals = []
    for c in range(poly.GetNumberOfCells()):
        ids = [poly.GetCell(c).GetPointId(k) for k in range(3)]
        a, b, d = pts[ids]
        n = np.cross(b - a, d - a)
        normals.append(n / np.linalg.norm(n))
    return np.array(normals)


class TestRadiosity(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.room = box_surface((0, 0, 0), (L, L, L), 3, True)
        add_albedo(cls.room, room_colour)
        cls.cube = marble_cube()

    def test_structure_and_bleeding(self):
        for kind in ("pdc", "multiblock"):
            if kind == "pdc":
                data = make_collection(self.room, self.cube)
            else:
                data = vtkMultiBlockDataSet()
                room = vtkPolyData()
                room.DeepCopy(self.room)  # its albedo is changed below
                data.SetBlock(0, room)
                data.SetBlock(1, self.cube)
            f = radiosity_filter(data)
            messages = Messages(f)
            f.Update()
            self.assertEqual(messages.errors, [])
            out = f.GetOutputDataObject(0)
            self.assertEqual(out.GetClassName(), data.GetClassName())
            parts = leaves(out)
            self.assertEqual(len(parts), 2)
            for part in parts:
                self.assertTrue(part.IsA("vtkPolyData"))
                for name in ("DirectIrradiance", "DirectRadiosity", "SubsurfaceRadiosity",
                             "InterReflectionRadiosity", "Radiosity"):
                    self.assertEqual(part.GetCellData().GetArray(name).GetNumberOfComponents(), 3)
                b = cell_array(part, "Radiosity")
                np.testing.assert_allclose(
                    b, cell_array(part, "SubsurfaceRadiosity")
                    + cell_array(part, "InterReflectionRadiosity"), rtol=1e-12, atol=1e-12)
            self.assertEqual(parts[0].GetNumberOfCells(), self.room.GetNumberOfCells())
            self.assertTrue(f.GetConverged())

        # Colour bleeding on the marble: faces towards the red wall (-x) are
        # redder than faces towards the green wall (+x).
        marble = parts[1]
        normals = face_normals(marble)
        b = cell_array(marble, "Radiosity")
        first = cell_array(marble, "SubsurfaceRadiosity")
        red_side = normals[:, 0] < -0.9
        green_side = normals[:, 0] > 0.9
        ratio = lambda sel, arr: arr[sel, 0].sum() / arr[sel, 1].sum()
        self.assertGreater(ratio(red_side, b), 1.1 * ratio(green_side, b))
        # White light, white-ish marble: the first bounce alone shows no such bleeding.
        self.assertLess(abs(ratio(red_side, first) - ratio(green_side, first)),
                        0.1 * ratio(green_side, first))

        # Relighting reuses the form factors.
        f.RemoveAllLights()
        f.AddPointLight(L / 2 + 2, L / 2, L - 1, 400, 400, 400)
        f.Update()
        self.assertEqual(f.GetFormFactorTime(), 0.0)
        self.assertGreater(f.GetFormFactorMemory(), 0)
        # ... and gives what a fresh filter gives (the kept scene is not stale).
        fresh = radiosity_filter(data)
        fresh.RemoveAllLights()
        fresh.AddPointLight(L / 2 + 2, L / 2, L - 1, 400, 400, 400)
        fresh.Update()
        for a, b in zip(leaves(f.GetOutputDataObject(0)), leaves(fresh.GetOutputDataObject(0))):
            np.testing.assert_allclose(cell_array(a, "Radiosity"), cell_array(b, "Radiosity"),
                                       rtol=1e-3, atol=1e-6 * cell_array(b, "Radiosity").max())
        # A changed albedo (array modified) is seen.
        before = cell_array(leaves(f.GetOutputDataObject(0))[0], "Radiosity").sum()
        room_albedo = data.GetBlock(0).GetCellData().GetArray("Albedo")
        for c in range(room_albedo.GetNumberOfTuples()):
            room_albedo.SetTuple3(c, 0.3, 0.3, 0.3)
        room_albedo.Modified()
        f.Modified()  # a composite input does not see its leaves' arrays change
        f.Update()
        self.assertEqual(f.GetFormFactorTime(), 0.0)
        self.assertLess(cell_array(leaves(f.GetOutputDataObject(0))[0], "Radiosity").sum(), before)

    def test_bad_input(self):
        room = vtkPolyData()
        room.DeepCopy(self.room)
        albedo = room.GetCellData().GetArray("Albedo")
        albedo.SetComponent(5, 1, 1.5)
        f = radiosity_filter(make_collection(room, self.cube))
        messages = Messages(f)
        f.Update()
        self.assertTrue(any("triangle 5 has albedo 1.5" in e for e in messages.errors),
                        messages.errors)

        f = radiosity_filter(make_collection(self.room, marble_cube(False)))
        messages = Messages(f)
        f.Update()
        self.assertTrue(any("translucent object without coefficients" in e
                            for e in messages.errors), messages.errors)

        block = box_surface((2, 2, 0.5), (5, 5, 4), 1, False)
        add_albedo(block, lambda x: (0.5, 0.5, 0.5))
        data = make_collection(self.room, self.cube)
        data.SetPartition(2, 0, block)
        data.GetMetaData(2).Set(vtkCompositeDataSet.NAME(), "block")
        f = radiosity_filter(data)
        f.RemoveAllLights()
        f.AddPointLight(3, 3, 2, 100, 100, 100)
        messages = Messages(f)
        f.Update()
        self.assertTrue(any("inside the closed opaque object 2 'block'" in e
                            for e in messages.errors), messages.errors)


class TestRadiosityCommandLine(unittest.TestCase):
    def run_cli(self, *args):
        from cli_under_test import find_cli
        return subprocess.run([find_cli("TestRadiosity"), "radiosity", *args],
                              capture_output=True, text=True)

    def test_missing_mesh_and_tiny_scene(self):
        with tempfile.TemporaryDirectory() as tmp:
            scene = {
                "cell_size": 5.0,
                "objects": [
                    {"name": "room", "type": "box", "min": [0, 0, 0], "max": [20, 20, 20],
                     "inward": True, "albedo": 0.6},
                    {"name": "statue", "file": "no_such_statue.ply", "translucent": True,
                     "material": "marble"}],
                "lights": [{"type": "point", "position": [10, 10, 18], "power": 100}]}
            path = os.path.join(tmp, "scene.json")
            with open(path, "w") as f:
                json.dump(scene, f)
            r = self.run_cli("--scene", path, "--output", os.path.join(tmp, "out"))
            self.assertEqual(r.returncode, 1, r.stderr)
            self.assertIn("no_such_statue.ply", r.stderr)
            self.assertIn("object 1 'statue'", r.stderr)

            scene["objects"][1] = {"name": "block", "type": "box", "min": [5, 5, 0.5],
                                   "max": [10, 10, 6], "translucent": True,
                                   "max_tet_volume": 2.0}
            with open(path, "w") as f:
                json.dump(scene, f)
            r = self.run_cli("--scene", path, "--output", os.path.join(tmp, "out"))
            self.assertEqual(r.returncode, 1, r.stderr)
            self.assertIn("translucent object without coefficients", r.stderr)

            scene["objects"][1]["material"] = {"absorption": [0.01, 0.02, 0.03],
                                               "scattering": [1, 1, 1], "eta": 1.3}
            with open(path, "w") as f:
                json.dump(scene, f)
            report = os.path.join(tmp, "report.json")
            r = self.run_cli("--scene", path, "--output", os.path.join(tmp, "out"),
                             "--json", report, "--rays", "64")
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(report) as f:
                data = json.load(f)
            self.assertTrue(data["converged"])
            self.assertGreater(data["patches"], 0)
            for k in range(2):
                self.assertTrue(os.path.exists(os.path.join(tmp, "out_%d.vtp" % k)))


if __name__ == "__main__":
    unittest.main()
