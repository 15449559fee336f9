#!/usr/bin/env python3
"""Tests of heterogeneous materials: translucency.vtkMaterialTableReader (the JSON
material table, Documentation/Materials.md) and the material modes of
translucency.vtkAssignScatteringCoefficients.

How to run (from a build tree):

    PYTHONPATH=<build>/lib/python3.11/site-packages \\
    TRANSLUCENCY_SOURCE_DIR=<source> /usr/bin/python3 TestMaterials.py

1. The shipped Data/materials.json reads back exactly the measured presets of
   vtkAssignScatteringCoefficients (compared value by value, ==).
2. A box [0, 4] x [0, 3] x [0, 2] mm split into 8 x 6 x 4 cubes of 6 tets
   each is the test mesh. Every expectation is computed here, independently
   of the filter: the table from json.load, centroids and their depth below
   the box surface (distance to the nearest face) analytically.
3. Id mode: a RegionAttribute cell array picks table entries per tet.
4. Spherical inclusion: exactly the tets whose centroid is in the ball get
   the inside material.
5. Layers: each tet gets the layer of its analytic centroid depth. Veins:
   without turbulence the analytic band formula; with it, the documented
   formula evaluated here with vtkPerlinNoise; seeds reproduce / differ.
6. Volume mode: a vtkImageData with a point field of mu_a, sigma_s' linear in
   x, y, z is reproduced exactly (trilinear interpolation) at each analytic
   centroid; a cell field gives the value of the voxel containing it; a
   material-id volume of two halves (cell ids, and point ids by nearest grid
   point) + a table gives each tet the entry of its half.
7. Bad input (missing file, malformed JSON, entry without coefficients,
   unknown preset, negative value, unknown id, ...) is one error message
   naming the file / entry / field / tet, and no crash.

Exits non-zero on failure (unittest).
"""

import functools
import sys
import itertools
import json
import math
import os
import subprocess
import tempfile
import unittest

import translucency
from vtkmodules.vtkCommonCore import vtkDoubleArray, vtkPoints
from vtkmodules.vtkCommonDataModel import vtkUnstructuredGrid

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import vtk_chain  # noqa: E402

# The executive's "returned failure" error is swallowed.
Messages = functools.partial(vtk_chain.Messages, executive="ignore")

VTK_TETRA = 10
SOURCE_DIR = os.environ.get(
    "TRANSLUCENCY_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
SHIPPED = os.path.join(SOURCE_DIR, "Data", "materials.json")
PRESETS = ["apple", "chicken1", "chicken2", "cream", "ketchup", "marble", "potato",
           "skimmilk", "skin1", "skin2", "spectralon", "wholemilk"]

# The volume mode's linear field: value = A + G . x per component.
VOL_A = ((0.01, 0.02, 0.03), (1.0, 1.5, 2.0))
VOL_G = (((0.001, 0.002, 0.003), (0.004, 0.0, 0.001), (0.002, 0.001, 0.0)),
         ((0.1, 0.2, 0.05), (0.3, 0.1, 0.2), (0.0, 0.05, 0.1)))


def linear_value(q, x):
    return tuple(VOL_A[q][c] + sum(VOL_G[q][c][a] * x[a] for a in range(3)) for c in range(3))


def image(origin, spacing, dims):
    from vtkmodules.vtkCommonDataModel import vtkImageData
    volume = vtkImageData()
    volume.SetOrigin(origin)
    volume.SetSpacing(spacing)
    volume.SetDimensions(dims)
    return volume


def add_array(data, name, values, components):
    array = vtkDoubleArray()
    array.SetName(name)
    array.SetNumberOfComponents(components)
    for v in values:
        array.InsertNextTuple(v if components > 1 else (v,))
    data.AddArray(array)
    return array


def linear_volume():
    """Point arrays of the linear fields on a grid covering the box (spacings not aligned)."""
    volume = image((-0.5, -0.5, -0.5), (0.7, 0.6, 0.9), (8, 7, 4))
    pts = [volume.GetPoint(p) for p in range(volume.GetNumberOfPoints())]
    add_array(volume.GetPointData(), "AbsorptionCoefficient",
              [linear_value(0, x) for x in pts], 3)
    add_array(volume.GetPointData(), "ReducedScatteringCoefficient",
              [linear_value(1, x) for x in pts], 3)
    return volume


# The box mesh: N cubes of edge H along each axis.
N = (8, 6, 4)
H = 0.5
BOX = tuple(n * H for n in N)


def box_mesh():
    """A tet mesh of the box: each cube split into 6 tets along its main diagonal."""
    grid = vtkUnstructuredGrid()
    points = vtkPoints()
    index = {}
    for k, j, i in itertools.product(range(N[2] + 1), range(N[1] + 1), range(N[0] + 1)):
        index[(i, j, k)] = points.InsertNextPoint(i * H, j * H, k * H)
    grid.SetPoints(points)
    for i, j, k in itertools.product(range(N[0]), range(N[1]), range(N[2])):
        for perm in itertools.permutations(range(3)):
            corner = [i, j, k]
            ids = [index[tuple(corner)]]
            for axis in perm:
                corner[axis] += 1
                ids.append(index[tuple(corner)])
            grid.InsertNextCell(VTK_TETRA, 4, ids)
    return grid


def centroids(grid):
    result = []
    for c in range(grid.GetNumberOfCells()):
        ids = grid.GetCell(c).GetPointIds()
        pts = [grid.GetPoint(ids.GetId(k)) for k in range(4)]
        result.append(tuple(sum(p[a] for p in pts) / 4.0 for a in range(3)))
    return result


def depth(x):
    """Distance from a point inside the box to the nearest box face."""
    return min(min(x[a], BOX[a] - x[a]) for a in range(3))


def coefficients(grid, c):
    cd = grid.GetCellData()
    return (cd.GetArray("AbsorptionCoefficient").GetTuple3(c),
            cd.GetArray("ReducedScatteringCoefficient").GetTuple3(c),
            cd.GetArray("RefractiveIndex").GetValue(c))


def preset_values(name):
    """The preset's (mu_a, sigma_s', eta) as the uniform mode assigns them."""
    assign = translucency.vtkAssignScatteringCoefficients()
    assign.SetMaterialName(name)
    grid = vtkUnstructuredGrid()
    points = vtkPoints()
    for p in ((0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)):
        points.InsertNextPoint(p)
    grid.SetPoints(points)
    grid.InsertNextCell(VTK_TETRA, 4, [0, 1, 2, 3])
    assign.SetInputData(grid)
    assign.Update()
    return coefficients(assign.GetOutput(), 0)


class MaterialsTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()

    def tearDown(self):
        self.tmp.cleanup()

    def write(self, name, text):
        path = os.path.join(self.tmp.name, name)
        with open(path, "w") as f:
            f.write(text if isinstance(text, str) else json.dumps(text))
        return path

    def read_table(self, path):
        reader = translucency.vtkMaterialTableReader()
        messages = Messages(reader)
        reader.SetFileName(path)
        reader.Update()
        return reader.GetOutput(), messages.errors

    def assign(self, grid, **settings):
        assign = translucency.vtkAssignScatteringCoefficients()
        messages = Messages(assign)
        for key, value in settings.items():
            if key == "volume":
                assign.SetVolumeData(value)
            elif key == "layers":
                for thickness, material in value:
                    assign.AddLayer(thickness, material)
            else:
                getattr(assign, "Set" + key)(value)
        assign.SetInputData(grid)
        assign.Update()
        return assign.GetOutput(), messages.errors

    # 1. The shipped table.
    def test_shipped_presets_round_trip(self):
        table, errors = self.read_table(SHIPPED)
        self.assertEqual(errors, [])
        self.assertEqual(table.GetNumberOfRows(), len(PRESETS))
        names = [table.GetColumnByName("Name").GetValue(r) for r in range(len(PRESETS))]
        self.assertEqual(sorted(names), PRESETS)
        for r, name in enumerate(names):
            mu_a, sigma_s, eta = preset_values(name)
            self.assertEqual(table.GetColumnByName("AbsorptionCoefficient").GetTuple3(r), mu_a, name)
            self.assertEqual(
                table.GetColumnByName("ReducedScatteringCoefficient").GetTuple3(r), sigma_s, name)
            self.assertEqual(table.GetColumnByName("RefractiveIndex").GetValue(r), eta, name)
            self.assertEqual(table.GetColumnByName("Id").GetValue(r), r + 1)
        # Two values straight from Jensen et al. 2001 (Materials.md, "Measured presets").
        marble = names.index("marble")
        self.assertEqual(table.GetColumnByName("ReducedScatteringCoefficient").GetTuple3(marble),
                         (2.19, 2.62, 3.00))
        skin1 = names.index("skin1")
        self.assertEqual(table.GetColumnByName("AbsorptionCoefficient").GetTuple3(skin1),
                         (0.032, 0.17, 0.48))

    def test_units_and_presets(self):
        path = self.write("cm.json", {"units": "1/cm", "materials": [
            {"name": "a", "absorption": [1, 2, 3], "reduced_scattering": [10, 20, 30]},
            {"id": 4, "preset": "Skin1"}]})
        table, errors = self.read_table(path)
        self.assertEqual(errors, [])
        absorption = table.GetColumnByName("AbsorptionCoefficient")
        self.assertEqual(absorption.GetTuple3(0), (0.1, 0.2, 0.30000000000000004))
        self.assertEqual(table.GetColumnByName("RefractiveIndex").GetValue(0), 1.3)
        self.assertEqual(table.GetColumnByName("Id").GetValue(0), -1)
        self.assertEqual(absorption.GetTuple3(1), preset_values("skin1")[0])  # presets stay 1/mm
        self.assertEqual(table.GetColumnByName("Id").GetValue(1), 4)

    # 3. Id mode.
    def test_id_mode(self):
        spec = {"units": "1/mm", "materials": [
            {"id": 3, "name": "red", "absorption": [0.5, 0.01, 0.02],
             "reduced_scattering": [1.0, 1.5, 2.0], "refractive_index": 1.4},
            {"id": 7, "preset": "ketchup"},
            {"id": 0, "absorption": [0.001, 0.002, 0.003], "reduced_scattering": [3, 2, 1]}]}
        path = self.write("table.json", spec)
        grid = box_mesh()
        region = vtkDoubleArray()
        region.SetName("RegionAttribute")
        ids = [(3, 7, 0)[(c * 7) % 3] for c in range(grid.GetNumberOfCells())]
        for v in ids:
            region.InsertNextValue(v)
        grid.GetCellData().AddArray(region)
        expected = {}
        for entry in spec["materials"]:
            if "preset" in entry:
                expected[entry["id"]] = preset_values(entry["preset"])
            else:
                expected[entry["id"]] = (tuple(entry["absorption"]),
                                         tuple(float(v) for v in entry["reduced_scattering"]),
                                         entry.get("refractive_index", 1.3))
        out, errors = self.assign(grid, MaterialMode=1, MaterialTableFileName=path)
        self.assertEqual(errors, [])
        for c, v in enumerate(ids):
            self.assertEqual(coefficients(out, c), expected[v], c)
        # The id array can have another name and an integer type.
        from vtkmodules.vtkCommonCore import vtkIntArray
        other = vtkIntArray()
        other.SetName("Label")
        for v in ids:
            other.InsertNextValue(v)
        grid.GetCellData().AddArray(other)
        grid.GetCellData().RemoveArray("RegionAttribute")
        out, errors = self.assign(grid, MaterialMode=1, MaterialTableFileName=path,
                                  MaterialIdArrayName="Label")
        self.assertEqual(errors, [])
        self.assertEqual(coefficients(out, 5), expected[ids[5]])

    # 4. Spherical inclusion.
    def test_spherical_inclusion(self):
        grid = box_mesh()
        center, radius = (2.1, 1.4, 0.9), 0.8
        out, errors = self.assign(grid, MaterialMode=2, InclusionCenter=center,
                                  InclusionRadius=radius, InsideMaterial="ketchup",
                                  OutsideMaterial="skin2")
        self.assertEqual(errors, [])
        inside, outside = preset_values("ketchup"), preset_values("skin2")
        count = 0
        for c, x in enumerate(centroids(grid)):
            d = math.dist(x, center)
            self.assertGreater(abs(d - radius), 1e-9)  # no tie at the sphere
            self.assertEqual(coefficients(out, c), inside if d < radius else outside, c)
            count += d < radius
        self.assertGreater(count, 10)

    def test_inclusion_with_table_references(self):
        path = self.write("t.json", {"materials": [
            {"id": 5, "name": "dark", "absorption": [1, 1, 1], "reduced_scattering": [1, 1, 1]}]})
        grid = box_mesh()
        out, errors = self.assign(grid, MaterialMode=2, MaterialTableFileName=path,
                                  InclusionCenter=(2, 1.5, 1), InclusionRadius=100.0,
                                  InsideMaterial="dark", OutsideMaterial="marble")
        self.assertEqual(errors, [])
        self.assertEqual(coefficients(out, 0), ((1, 1, 1), (1, 1, 1), 1.3))
        out, errors = self.assign(grid, MaterialMode=2, MaterialTableFileName=path,
                                  InclusionRadius=100.0, InsideMaterial="5")
        self.assertEqual(errors, [])
        self.assertEqual(coefficients(out, 0), ((1, 1, 1), (1, 1, 1), 1.3))

    # 5. Layers.
    def test_layers(self):
        grid = box_mesh()
        layers = [(0.3, "skin1"), (0.4, "skin2"), (1.0, "marble")]
        out, errors = self.assign(grid, MaterialMode=3, layers=layers)
        self.assertEqual(errors, [])
        values = [preset_values(m) for _, m in layers]
        counts = [0, 0, 0]
        for c, x in enumerate(centroids(grid)):
            d = depth(x)
            self.assertGreater(min(abs(d - 0.3), abs(d - 0.7)), 1e-9)  # no tie at a layer bottom
            layer = 0 if d < 0.3 else 1 if d < 0.7 else 2
            counts[layer] += 1
            self.assertEqual(coefficients(out, c), values[layer], (c, x, d))
        self.assertTrue(all(counts), counts)

    # 5b. Veins.
    def vein_expectation(self, grid, base, vein, direction, f, octaves, turbulence, sharpness,
                         seed):
        """The documented formula, evaluated here with vtkPerlinNoise."""
        from vtkmodules.vtkCommonDataModel import vtkPerlinNoise
        norm = math.sqrt(sum(a * a for a in direction))
        d = [a / norm for a in direction]
        golden = (0.7548776662466927, 0.5698402909980532, 0.4301597090019468)
        noise = vtkPerlinNoise()
        noise.SetAmplitude(1.0)
        noise.SetPhase([seed * g - math.floor(seed * g) for g in golden])
        b, v = preset_values(base), preset_values(vein)
        result = []
        for x in centroids(grid):
            t = 0.0
            for o in range(octaves):
                noise.SetFrequency(f * 2 ** o, f * 2 ** o, f * 2 ** o)
                t += abs(noise.EvaluateFunction(x)) / 2 ** o
            s = math.sin(2 * math.pi * (f * sum(a * c for a, c in zip(d, x)) + turbulence * t))
            w = (1 - abs(s)) ** sharpness
            result.append((w, [tuple((1 - w) * p + w * q for p, q in zip(b[k], v[k]))
                               for k in range(2)] + [(1 - w) * b[2] + w * v[2]]))
        return result

    def assert_close(self, actual, expected, context):
        self.assertEqual(len(actual[0]), 3)
        for k in range(2):
            for a, e in zip(actual[k], expected[k]):
                self.assertAlmostEqual(a, e, delta=1e-12 * max(1.0, abs(e)), msg=context)
        self.assertAlmostEqual(actual[2], expected[2], delta=1e-12, msg=context)

    def test_veins_straight_bands(self):
        # Without turbulence the veins are planes: w = (1 - |sin(2 pi f d.x)|)^k.
        grid = box_mesh()
        f, k, direction = 0.37, 2.0, (1.0, 2.0, 0.5)
        out, errors = self.assign(grid, MaterialMode=4, BaseMaterial="marble",
                                  VeinMaterial="ketchup", VeinDirection=direction,
                                  VeinFrequency=f, VeinTurbulence=0.0, VeinSharpness=k)
        self.assertEqual(errors, [])
        norm = math.sqrt(sum(a * a for a in direction))
        b, v = preset_values("marble"), preset_values("ketchup")
        weights = []
        for c, x in enumerate(centroids(grid)):
            s = math.sin(2 * math.pi * f * sum(a * y for a, y in zip(direction, x)) / norm)
            w = (1 - abs(s)) ** k
            weights.append(w)
            expected = [tuple((1 - w) * p + w * q for p, q in zip(b[i], v[i])) for i in range(2)]
            self.assert_close(coefficients(out, c), expected + [(1 - w) * b[2] + w * v[2]], c)
        self.assertGreater(max(weights), 0.9)
        self.assertLess(min(weights), 0.01)

    def test_veins_turbulence(self):
        grid = box_mesh()
        settings = dict(MaterialMode=4, BaseMaterial="marble", VeinMaterial="chicken1",
                        VeinDirection=(0.0, 0.0, 1.0), VeinFrequency=0.3, VeinOctaves=3,
                        VeinTurbulence=2.0, VeinSharpness=4.0, VeinSeed=7)
        out, errors = self.assign(grid, **settings)
        self.assertEqual(errors, [])
        expected = self.vein_expectation(grid, "marble", "chicken1", (0, 0, 1), 0.3, 3, 2.0, 4.0, 7)
        for c, (w, e) in enumerate(expected):
            self.assert_close(coefficients(out, c), e, c)
        # The noise bends the bands: the weights differ from the straight ones.
        straight = [(1 - abs(math.sin(2 * math.pi * 0.3 * x[2]))) ** 4 for x in centroids(grid)]
        self.assertGreater(max(abs(w - s) for (w, _), s in zip(expected, straight)), 0.05)
        # Same seed: same result; another seed: another pattern.
        again, _ = self.assign(grid, **settings)
        self.assertEqual([coefficients(again, c) for c in range(0, 1152, 97)],
                         [coefficients(out, c) for c in range(0, 1152, 97)])
        settings["VeinSeed"] = 8
        other, _ = self.assign(grid, **settings)
        self.assertNotEqual([coefficients(other, c) for c in range(1152)],
                            [coefficients(out, c) for c in range(1152)])

    def test_veins_bad_settings(self):
        out, errors = self.assign(box_mesh(), MaterialMode=4, VeinDirection=(0, 0, 0))
        self.assertEqual(len(errors), 1, errors)
        self.assertIn("direction", errors[0])
        out, errors = self.assign(box_mesh(), MaterialMode=4, VeinFrequency=-1.0)
        self.assertIn("frequency", errors[0])
        out, errors = self.assign(box_mesh(), MaterialMode=4, VeinMaterial="granite")
        self.assertIn("granite", errors[0])

    def test_default_mode_unchanged(self):
        out, errors = self.assign(box_mesh())
        self.assertEqual(errors, [])
        self.assertEqual(coefficients(out, 17), preset_values("marble"))
        self.assertEqual(coefficients(out, 17)[1], (2.19, 2.62, 3.00))

    # 6. Bad input.
    def assert_table_error(self, text, *patterns):
        path = self.write("bad.json", text)
        table, errors = self.read_table(path)
        self.assertEqual(len(errors), 1, errors)
        self.assertIn("bad.json", errors[0])
        for p in patterns:
            self.assertRegex(errors[0], p)
        self.assertEqual(table.GetNumberOfRows(), 0)
        # The filter reports the same error and does not crash.
        out, ferrors = self.assign(box_mesh(), MaterialMode=1, MaterialTableFileName=path)
        self.assertEqual(len(ferrors), 1, ferrors)
        self.assertIn("bad.json", ferrors[0])
        self.assertEqual(out.GetNumberOfCells(), 0)
        return errors[0]

    def test_missing_file(self):
        path = os.path.join(self.tmp.name, "nothere.json")
        table, errors = self.read_table(path)
        self.assertEqual(len(errors), 1, errors)
        self.assertIn("nothere.json", errors[0])
        self.assertIn("cannot open", errors[0])

    def test_malformed_json(self):
        self.assert_table_error('{"materials": [ {"name": "a", ', "not valid JSON")

    def test_not_a_table(self):
        self.assert_table_error('[1, 2]', '"materials"')

    def test_entry_without_coefficients(self):
        self.assert_table_error({"materials": [
            {"name": "ok", "preset": "marble"}, {"name": "empty", "id": 2}]},
            r"entry 1 \(\"empty\"\)", "preset", "absorption")

    def test_unknown_preset(self):
        self.assert_table_error({"materials": [{"id": 1, "preset": "granite"}]},
                                "entry 0", "granite")

    def test_negative_value(self):
        self.assert_table_error({"materials": [
            {"name": "m", "absorption": [0.1, -0.2, 0.3], "reduced_scattering": [1, 1, 1]}]},
            "entry 0", r'"absorption"\[1\]', "-0.2")

    def test_bad_fields(self):
        self.assert_table_error({"materials": [{"id": 1.5, "preset": "marble"}]}, '"id"', "1.5")
        self.assert_table_error({"materials": [{"id": 1, "preset": "marble"},
                                               {"id": 1, "preset": "skin1"}]}, "duplicate", "entry 1")
        self.assert_table_error({"materials": [{"id": 1, "preset": "marble", "absorption": [1, 1, 1]}]},
                                "both")
        self.assert_table_error({"materials": [{"id": 1, "absorption": [1, 1],
                                                "reduced_scattering": [1, 1, 1]}]}, r"\[r, g, b\]")
        self.assert_table_error({"units": "1/in", "materials": [{"id": 1, "preset": "marble"}]},
                                "units")
        self.assert_table_error({"materials": [{"id": 1, "preset": "marble", "colour": 3}]},
                                "colour")

    def test_unknown_id(self):
        path = self.write("ids.json", {"materials": [{"id": 1, "preset": "marble"}]})
        grid = box_mesh()
        region = vtkDoubleArray()
        region.SetName("RegionAttribute")
        for c in range(grid.GetNumberOfCells()):
            region.InsertNextValue(1 if c != 40 else 9)
        grid.GetCellData().AddArray(region)
        out, errors = self.assign(grid, MaterialMode=1, MaterialTableFileName=path)
        self.assertEqual(len(errors), 1, errors)
        self.assertRegex(errors[0], r"tet 40 has material id 9\b")
        self.assertIn("ids.json", errors[0])
        self.assertEqual(out.GetNumberOfCells(), 0)
        region.SetValue(40, 1.5)
        region.Modified()
        out, errors = self.assign(grid, MaterialMode=1, MaterialTableFileName=path)
        self.assertRegex(errors[0], r"tet 40 has material id 1.5")
        # No id array at all.
        out, errors = self.assign(grid, MaterialMode=1, MaterialTableFileName=path,
                                  MaterialIdArrayName="Nope")
        self.assertRegex(errors[0], "'Nope'")

    def test_bad_procedural_settings(self):
        grid = box_mesh()
        out, errors = self.assign(grid, MaterialMode=2, InsideMaterial="granite")
        self.assertEqual(len(errors), 1, errors)
        self.assertIn("granite", errors[0])
        out, errors = self.assign(grid, MaterialMode=3)
        self.assertIn("layer", errors[0])
        out, errors = self.assign(grid, MaterialMode=3, layers=[(-1.0, "marble")])
        self.assertIn("-1", errors[0])
        out, errors = self.assign(grid, MaterialMode=1)
        self.assertIn("material table", errors[0])

    # 6. Volume mode.
    def test_volume_linear_field(self):
        grid = box_mesh()
        out, errors = self.assign(grid, MaterialMode=5, volume=linear_volume(),
                                  RefractiveIndex=1.45, ScaleFactor=2.0)
        self.assertEqual(errors, [])
        self.assertEqual(out.GetNumberOfCells(), grid.GetNumberOfCells())
        for c, x in enumerate(centroids(grid)):
            mu_a, sigma_s, eta = coefficients(out, c)
            for q, actual in enumerate((mu_a, sigma_s)):
                for a, e in zip(actual, linear_value(q, x)):
                    self.assertAlmostEqual(a, 2.0 * e, delta=1e-12 * max(1.0, abs(e)), msg=c)
            self.assertEqual(eta, 1.45)

    def test_volume_cell_field(self):
        grid = box_mesh()
        volume = image((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (5, 4, 3))  # 4 x 3 x 2 voxels
        voxels = [(i, j, k) for k in range(2) for j in range(3) for i in range(4)]
        add_array(volume.GetCellData(), "mua", [(0.01 * i, 0.02 * j, 0.03 * k)
                                                for i, j, k in voxels], 3)
        add_array(volume.GetCellData(), "mus", [(1 + i, 2 + j, 3 + k) for i, j, k in voxels], 3)
        out, errors = self.assign(grid, MaterialMode=5, volume=volume,
                                  VolumeAbsorptionArrayName="mua", VolumeScatteringArrayName="mus")
        self.assertEqual(errors, [])
        for c, x in enumerate(centroids(grid)):
            i, j, k = (int(math.floor(v)) for v in x)
            mu_a, sigma_s, eta = coefficients(out, c)
            self.assertEqual(mu_a, (0.01 * i, 0.02 * j, 0.03 * k), c)
            self.assertEqual(sigma_s, (1 + i, 2 + j, 3 + k), c)
            self.assertEqual(eta, 1.3)

    def test_volume_material_ids(self):
        path = self.write("halves.json", {"materials": [
            {"id": 1, "preset": "skin1"},
            {"id": 2, "name": "b", "absorption": [0.01, 0.02, 0.03],
             "reduced_scattering": [1, 2, 3], "refractive_index": 1.5}]})
        expected = {1: preset_values("skin1"), 2: ((0.01, 0.02, 0.03), (1.0, 2.0, 3.0), 1.5)}
        grid = box_mesh()
        cells = centroids(grid)
        # Cell ids: the voxels [0, 2] x ... are id 1, [2, 4] x ... id 2 (no centroid has x = 2).
        volume = image((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (5, 4, 3))
        add_array(volume.GetCellData(), "Tissue",
                  [1 if i < 2 else 2 for k in range(2) for j in range(3) for i in range(4)], 1)
        self.assertFalse(any(x[0] == 2.0 for x in cells))
        out, errors = self.assign(grid, MaterialMode=5, volume=volume,
                                  VolumeMaterialIdArrayName="Tissue", MaterialTableFileName=path,
                                  RefractiveIndex=1.1)
        self.assertEqual(errors, [])
        halves = set()
        for c, x in enumerate(cells):
            half = 1 if x[0] < 2.0 else 2
            halves.add(half)
            self.assertEqual(coefficients(out, c), expected[half], c)
        self.assertEqual(halves, {1, 2})
        # Point ids: the nearest grid point (x = 0, 1 -> id 1; 2, 3, 4 -> id 2), no
        # interpolation; no centroid is half-way between grid points.
        volume = image((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (5, 4, 3))
        add_array(volume.GetPointData(), "Tissue",
                  [1 if i < 2 else 2 for k in range(3) for j in range(4) for i in range(5)], 1)
        self.assertFalse(any(x[0] % 1.0 == 0.5 for x in cells))
        out, errors = self.assign(grid, MaterialMode=5, volume=volume,
                                  VolumeMaterialIdArrayName="Tissue", MaterialTableFileName=path)
        self.assertEqual(errors, [])
        for c, x in enumerate(cells):
            self.assertEqual(coefficients(out, c), expected[1 if round(x[0]) < 2 else 2], c)

    def test_volume_bad_input(self):
        grid = box_mesh()
        out, errors = self.assign(grid, MaterialMode=5)
        self.assertEqual(len(errors), 1, errors)
        self.assertIn("second input port", errors[0])
        self.assertEqual(out.GetNumberOfCells(), 0)
        out, errors = self.assign(grid, MaterialMode=5, volume=linear_volume(),
                                  VolumeScatteringArrayName="Nope")
        self.assertEqual(len(errors), 1, errors)
        self.assertIn("'Nope'", errors[0])
        volume = linear_volume()
        add_array(volume.GetPointData(), "one", [0.5] * volume.GetNumberOfPoints(), 1)
        out, errors = self.assign(grid, MaterialMode=5, volume=volume,
                                  VolumeAbsorptionArrayName="one")
        self.assertRegex(errors[0], r"'one'.* 1 components, not 3")
        # A volume not covering the box: the first tet with its centroid beyond x = 3.
        small = image((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (4, 4, 3))
        add_array(small.GetPointData(), "AbsorptionCoefficient",
                  [(0.1, 0.1, 0.1)] * small.GetNumberOfPoints(), 3)
        add_array(small.GetPointData(), "ReducedScatteringCoefficient",
                  [(1, 1, 1)] * small.GetNumberOfPoints(), 3)
        out, errors = self.assign(grid, MaterialMode=5, volume=small)
        first = next(c for c, x in enumerate(centroids(grid)) if x[0] > 3.0)
        x = centroids(grid)[first]
        self.assertEqual(len(errors), 1, errors)
        self.assertRegex(errors[0], r"tet %d has its centroid \(%s, %s, %s\) outside the volume"
                         % ((first,) + tuple(repr(v) for v in x)))
        self.assertEqual(out.GetNumberOfCells(), 0)
        # Negative and NaN values at grid point 9 = (1, 1, 0), a corner of the voxel of
        # tet 0's centroid (0.375, 0.25, 0.125).
        for bad in (-1000.0, float("nan")):
            volume = linear_volume()
            self.assertEqual(volume.ComputeStructuredCoordinates(centroids(grid)[0], [0] * 3,
                                                                 [0.0] * 3), 1)
            volume.GetPointData().GetArray("ReducedScatteringCoefficient").SetComponent(9, 1, bad)
            out, errors = self.assign(grid, MaterialMode=5, volume=volume)
            self.assertEqual(len(errors), 1, errors)
            self.assertRegex(errors[0], r"tet 0 gets the value (-|nan).*'ReducedScattering")
            self.assertEqual(out.GetNumberOfCells(), 0)
        # Material ids: no table, an id absent from the table, a missing array.
        volume = image((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (5, 4, 3))
        add_array(volume.GetCellData(), "Tissue", [1] * 23 + [5], 1)
        out, errors = self.assign(grid, MaterialMode=5, volume=volume,
                                  VolumeMaterialIdArrayName="Tissue")
        self.assertIn("material table", errors[0])
        path = self.write("one.json", {"materials": [{"id": 1, "preset": "marble"}]})
        out, errors = self.assign(grid, MaterialMode=5, volume=volume,
                                  VolumeMaterialIdArrayName="Tissue", MaterialTableFileName=path)
        self.assertEqual(len(errors), 1, errors)
        self.assertRegex(errors[0], r"tet \d+ has material id 5 .*'Tissue'.*one.json")
        out, errors = self.assign(grid, MaterialMode=5, volume=volume,
                                  VolumeMaterialIdArrayName="Nope", MaterialTableFileName=path)
        self.assertIn("'Nope'", errors[0])

    # 8. The command line: --material TABLE.json --material-ids ARRAY.
    def test_command_line(self):
        from cli_under_test import find_cli
        cli = find_cli("TestMaterials")
        grid = box_mesh()
        base = os.path.join(self.tmp.name, "box")
        with open(base + ".node", "w") as f:
            f.write("%d 3 0 0\n" % grid.GetNumberOfPoints())
            for i in range(grid.GetNumberOfPoints()):
                f.write("%d %.17g %.17g %.17g\n" % ((i,) + grid.GetPoint(i)))
        region = [1 + (c % 3) for c in range(grid.GetNumberOfCells())]
        with open(base + ".ele", "w") as f:
            f.write("%d 4 1\n" % grid.GetNumberOfCells())
            for c in range(grid.GetNumberOfCells()):
                ids = grid.GetCell(c).GetPointIds()
                f.write("%d %s %d\n" % (c, " ".join(str(ids.GetId(k)) for k in range(4)),
                                         region[c]))
        table = self.write("cli.json", {"materials": [
            {"id": 1, "preset": "skin1"}, {"id": 2, "preset": "marble"},
            {"id": 3, "name": "x", "absorption": [0.01, 0.02, 0.03],
             "reduced_scattering": [1, 2, 3], "refractive_index": 1.4}]})
        prefix = os.path.join(self.tmp.name, "out")
        args = [cli, "render", "--mesh", base + ".node", "--output", prefix, "--light", "uniform:1",
                "--uniform-samples", "0"]
        run = subprocess.run(args + ["--material", table, "--material-ids", "RegionAttribute"],
                             capture_output=True, text=True, timeout=300)
        self.assertEqual(run.returncode, 0, run.stderr)
        from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
        reader = vtkXMLUnstructuredGridReader()
        reader.SetFileName(prefix + ".vtu")
        reader.Update()
        out = reader.GetOutput()
        expected = {1: preset_values("skin1"), 2: preset_values("marble"),
                    3: ((0.01, 0.02, 0.03), (1.0, 2.0, 3.0), 1.4)}
        regions = out.GetCellData().GetArray("RegionAttribute")
        self.assertEqual(out.GetNumberOfCells(), grid.GetNumberOfCells())
        for c in range(out.GetNumberOfCells()):
            self.assertEqual(coefficients(out, c), expected[int(regions.GetValue(c))], c)
        # A table without --material-ids, an id missing from the table, a
        # single material with --material-ids: clear failures.
        run = subprocess.run(args + ["--material", table], capture_output=True, text=True,
                             timeout=300)
        self.assertGreater(run.returncode, 0)
        self.assertIn("--material-ids", run.stderr)
        small = self.write("small.json", {"materials": [{"id": 1, "preset": "skin1"}]})
        run = subprocess.run(args + ["--material", small, "--material-ids", "RegionAttribute"],
                             capture_output=True, text=True, timeout=300)
        self.assertGreater(run.returncode, 0)
        self.assertRegex(run.stderr, r"tet \d+ has material id 2")
        run = subprocess.run(args + ["--material", "marble", "--material-ids", "RegionAttribute"],
                             capture_output=True, text=True, timeout=300)
        self.assertGreater(run.returncode, 0)
        self.assertIn("material table", run.stderr)


if __name__ == "__main__":
    unittest.main()
