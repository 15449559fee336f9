"""Test of the Translucency ParaView plugin, run by pvpython.

How to run (ctest does this):

    pvpython --force-offscreen-rendering TestPlugin.py <build>/lib/paraview-plugins/Translucency/Translucency.so

1. Loads the plugin and applies the chain of its proxies to a Sphere source:
   Triangulate -> TetrahedralizeSurface -> AssignScatteringCoefficients ->
   SurfaceIrradiance -> SolveDiffusion -> OutgoingRadiance.
2. Fetches the results and checks the arrays of the data contract, Fluence > 0,
   and that the proxy properties reach the filters: a material preset, the
   repeated DirectionalLights property (doubling the light doubles the
   fluence, two lights add up: the diffusion problem is linear in q).
3. The Volume material mode: a Wavelet image with linear coefficient fields
   (Calculator) on the optional Volume input gives the fields at the tet
   centroids (trilinear probe of a linear field is exact).
4. Paint Scattering Coefficients (its CutoffWeight) and Solve Diffusion's
   incremental assembly after a paint (IncrementalAssembly).
5. Reads a small TetGen mesh written here with the TetGenReader proxy, both
   directly and through OpenDataFile (the plugin's reader factory hint).
6. Reads Data/bunny.ply with the TranslucencySurfaceReader proxy and, with the
   plugin loaded, still through OpenDataFile; a damaged copy gives an error,
   not a crash.

Exits non-zero on failure (unittest). No rendering.
"""

import os
import sys
import tempfile
import unittest

from paraview.simple import *  # noqa: F401,F403
from paraview import servermanager

if len(sys.argv) < 2 or not os.path.isfile(sys.argv[1]):
    sys.exit("usage: pvpython --force-offscreen-rendering TestPlugin.py <Translucency plugin>")
PLUGIN = sys.argv[1]
LoadPlugin(PLUGIN, ns=globals())

# paraview.simple names a proxy's function after its label: the label
# The proxy label "Tetrahedralize Surface" gives the paraview.simple name TetrahedralizeSurface.
Tetrahedralize = TetrahedralizeSurface

from vtkmodules.util.numpy_support import vtk_to_numpy  # noqa: E402
from vtkmodules.vtkCommonCore import vtkObject  # noqa: E402
import numpy as np  # noqa: E402

VTK_TETRA = 10


def point_array(data, name):
    a = data.GetPointData().GetArray(name)
    if a is None:
        raise AssertionError("no point array '%s'" % name)
    return vtk_to_numpy(a)


def cell_array(data, name):
    a = data.GetCellData().GetArray(name)
    if a is None:
        raise AssertionError("no cell array '%s'" % name)
    return vtk_to_numpy(a)


class PluginTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.sphere = Sphere(Radius=4.0, ThetaResolution=12, PhiResolution=12)
        cls.triangles = Triangulate(Input=cls.sphere)
        cls.tetra = Tetrahedralize(Input=cls.triangles, TargetNumberOfTets=1500)
        cls.assign = AssignScatteringCoefficients(Input=cls.tetra)
        # The surface model: the incremental paint path below is its (the
        # default by light kind assembles the extended model in full).
        cls.irradiance = SurfaceIrradiance(Input=cls.assign, CollimatedModel=0)
        cls.solve = SolveDiffusion(Input=cls.irradiance)
        cls.radiance = OutgoingRadiance(Input=cls.solve)

    def fetch(self, proxy):
        proxy.UpdatePipeline()
        return servermanager.Fetch(proxy)

    def test_chain(self):
        surface = self.fetch(self.radiance)
        grid = self.fetch(self.solve)
        self.assertEqual(grid.GetClassName(), "vtkUnstructuredGrid")
        self.assertGreater(grid.GetNumberOfCells(), 500)
        self.assertTrue(all(grid.GetCellType(i) == VTK_TETRA for i in range(grid.GetNumberOfCells())))
        for name, components in (("AbsorptionCoefficient", 3), ("ReducedScatteringCoefficient", 3),
                                 ("RefractiveIndex", 1), ("vtkOriginalCellIds", 1)):
            self.assertEqual(grid.GetCellData().GetArray(name).GetNumberOfComponents(), components,
                             name)
        # The XML's defaults: marble (Materials.md: mu_a = (0.0021, 0.0041, 0.0071) 1/mm, eta 1.3).
        self.assertTrue(np.allclose(cell_array(grid, "AbsorptionCoefficient"),
                                    [0.0021, 0.0041, 0.0071], rtol=1e-12))
        self.assertTrue(np.allclose(cell_array(grid, "RefractiveIndex"), 1.3, rtol=1e-12))
        for name in ("Irradiance", "Fluence"):
            self.assertEqual(grid.GetPointData().GetArray(name).GetNumberOfComponents(), 3, name)
        fluence = point_array(grid, "Fluence")
        self.assertTrue(np.all(np.isfinite(fluence)) and np.all(fluence > 0.0))
        self.assertEqual(surface.GetClassName(), "vtkPolyData")
        self.assertGreater(surface.GetNumberOfCells(), 0)
        for name in ("Radiance", "Fluence", "Irradiance"):
            self.assertEqual(surface.GetPointData().GetArray(name).GetNumberOfComponents(), 3, name)
        self.assertTrue(np.all(point_array(surface, "Radiance") >= 0.0))
        self.assertGreater(np.max(point_array(surface, "Radiance")), 0.0)

    def test_sources_detectors_frequency(self):
        """PointSources, PencilBeams, Detectors, ModulationFrequency (DiffuseOptics.md)."""
        solve = SolveDiffusion(Input=self.irradiance, Solver="fem", RelTol=1e-10)
        try:
            solve.PointSources = [0, 0, 0, 1, 1, 1, 1, 0.5, 0, 2, 2, 2]
            solve.PencilBeams = [0, 0, 4, 0, 0, -1, 1, 1, 1]
            solve.Detectors = [4, 0, 0, 0, 0, 4, 0, 1]
            grid = self.fetch(solve)
            fluence = grid.GetFieldData().GetArray("DetectorFluence")
            exitance = grid.GetFieldData().GetArray("DetectorExitance")
            self.assertEqual(fluence.GetNumberOfTuples(), 2)
            self.assertTrue(np.all(vtk_to_numpy(exitance) > 0.0))
            self.assertTrue(np.all(vtk_to_numpy(fluence) > vtk_to_numpy(exitance)))
            with_sources = point_array(grid, "Fluence")
            self.assertIsNone(grid.GetPointData().GetArray("FluencePhase"))
            solve.ModulationFrequency = 100e6
            grid = self.fetch(solve)
            self.assertEqual(grid.GetPointData().GetArray("FluencePhase").GetNumberOfComponents(), 3)
            self.assertTrue(np.all(point_array(grid, "FluenceAmplitude") <= with_sources * 1.001))
            self.assertIsNotNone(grid.GetFieldData().GetArray("DetectorFluencePhase"))
            # Clearing one kind keeps the other: fewer sources, less light.
            solve.ModulationFrequency = 0
            solve.PointSources = []
            grid = self.fetch(solve)
            self.assertLess(np.sum(point_array(grid, "Fluence")), np.sum(with_sources))
        finally:
            Delete(solve)

    def test_material_property(self):
        self.assign.MaterialName = "skin1"
        try:
            grid = self.fetch(self.assign)
            self.assertTrue(np.allclose(cell_array(grid, "AbsorptionCoefficient"),
                                        [0.032, 0.17, 0.48], rtol=1e-12))
            self.assertTrue(np.allclose(cell_array(grid, "ReducedScatteringCoefficient"),
                                        [0.74, 0.88, 1.01], rtol=1e-12))
            # Explicit coefficients when the name is empty.
            self.assign.MaterialName = ""
            self.assign.AbsorptionCoefficient = [0.1, 0.2, 0.3]
            self.assign.ReducedScatteringCoefficient = [1.0, 2.0, 3.0]
            self.assign.RefractiveIndex = 1.5
            grid = self.fetch(self.assign)
            self.assertTrue(np.allclose(cell_array(grid, "AbsorptionCoefficient"), [0.1, 0.2, 0.3]))
            self.assertTrue(np.allclose(cell_array(grid, "RefractiveIndex"), 1.5))
        finally:
            self.assign.MaterialName = "marble"

    def test_volume_material(self):
        # A vtkImageData (Wavelet, bounds [-10, 10]^3) with linear 3-component
        # fields: the trilinear probe reproduces them exactly at each centroid.
        wavelet = Wavelet()
        absorption = Calculator(Input=wavelet, ResultArrayName="AbsorptionCoefficient",
                                ResultArrayType="Double",
                                Function="(0.01 + 0.001*(coordsX+10))*iHat + "
                                         "(0.02 + 0.002*(coordsY+10))*jHat + 0.03*kHat")
        scattering = Calculator(Input=absorption, ResultArrayName="ReducedScatteringCoefficient",
                                ResultArrayType="Double",
                                Function="(1 + 0.05*(coordsZ+10))*iHat + 2*jHat + 3*kHat")
        assign = AssignScatteringCoefficients(Input=self.tetra, MaterialMode="Volume",
                                              Volume=scattering)
        try:
            volume = self.fetch(scattering)
            self.assertEqual(volume.GetClassName(), "vtkImageData")
            mesh = self.fetch(assign)
            points = vtk_to_numpy(mesh.GetPoints().GetData()).astype(float)
            tets = vtk_to_numpy(mesh.GetCells().GetConnectivityArray()).reshape(-1, 4)
            x = points[tets].mean(axis=1)
            expected_a = np.stack([0.01 + 0.001 * (x[:, 0] + 10), 0.02 + 0.002 * (x[:, 1] + 10),
                                   np.full(len(x), 0.03)], axis=1)
            expected_s = np.stack([1 + 0.05 * (x[:, 2] + 10), np.full(len(x), 2.0),
                                   np.full(len(x), 3.0)], axis=1)
            self.assertGreater(np.ptp(expected_a[:, 0]), 0.005)  # the field varies
            self.assertTrue(np.allclose(cell_array(mesh, "AbsorptionCoefficient"), expected_a,
                                        rtol=1e-9, atol=0))
            self.assertTrue(np.allclose(cell_array(mesh, "ReducedScatteringCoefficient"),
                                        expected_s, rtol=1e-9, atol=0))
            # The array-name properties reach the filter: a missing array fails.
            assign.VolumeAbsorptionArrayName = "NoSuchArray"
            assign.UpdatePipeline()
            self.assertEqual(servermanager.Fetch(assign).GetNumberOfCells(), 0)
        finally:
            for proxy in (assign, scattering, absorption, wavelet):
                Delete(proxy)

    def test_paint_then_incremental_solve(self):
        # The Paint proxy (CutoffWeight reaches the filter: weights vanish
        # beyond the cut-off radius, none with CutoffWeight 0) and a second
        # solve that rebuilds only the painted rows (IncrementalAssembly).
        paint = PaintScatteringCoefficients(Input=self.irradiance, StrokePoints=[3.5, 0.0, 0.0],
                                            Width=0.3)
        solve = SolveDiffusion(Input=paint, RelTol=1e-12)
        try:
            grid = self.fetch(paint)
            weights = cell_array(grid, "PaintWeight")
            self.assertGreater(np.count_nonzero(weights == 0.0), 10)
            self.assertGreater(np.count_nonzero(weights > 0.2), 0)
            paint.CutoffWeight = 0.0
            self.assertTrue(np.all(cell_array(self.fetch(paint), "PaintWeight") > 0.0))
            paint.CutoffWeight = 1e-6
            paint.Strength = 0.0
            self.fetch(solve)
            import translucency  # noqa: F401  (Python wrappers of the filters)
            vtk_solve = solve.GetClientSideObject()
            self.assertEqual(vtk_solve.GetLastAssembly(), "full")
            paint.Strength = 1.0
            paint.Width = 0.2
            phi = point_array(self.fetch(solve), "Fluence").copy()
            self.assertEqual(vtk_solve.GetLastAssembly(), "incremental")
            self.assertGreater(vtk_solve.GetNumberOfChangedTets(), 0)
            solve.IncrementalAssembly = 0
            solve.RelTol = 1e-13  # forces a re-execution
            self.assertEqual(solve.GetProperty("IncrementalAssembly").GetElement(0), 0)
            full = point_array(self.fetch(solve), "Fluence")
            self.assertEqual(vtk_solve.GetLastAssembly(), "full")
            self.assertTrue(np.allclose(phi, full, rtol=1e-7, atol=0))
        finally:
            for proxy in (solve, paint):
                Delete(proxy)

    def test_lights_are_linear(self):
        # q is linear in the light powers, phi linear in q.
        self.irradiance.UniformLightIrradiance = 0.0
        self.solve.RelTol = 1e-11
        try:
            def fluence(lights):
                self.irradiance.DirectionalLights = lights
                return point_array(self.fetch(self.solve), "Fluence").copy()

            one = fluence([0, -1, -1, 1.0])
            two = fluence([0, -1, -1, 2.0])
            other = fluence([1, 0, 0, 1.0])
            both = fluence([0, -1, -1, 1.0, 1, 0, 0, 1.0])
            scale = np.max(np.abs(both))
            self.assertGreater(np.max(np.abs(one - other)), 1e-3 * scale, "the lights differ")
            self.assertTrue(np.allclose(two, 2.0 * one, rtol=0, atol=1e-8 * scale))
            self.assertTrue(np.allclose(both, one + other, rtol=0, atol=1e-8 * scale))
        finally:
            self.irradiance.DirectionalLights = [0, -1, -1, 1]
            self.irradiance.UniformLightIrradiance = 0.1
            self.solve.RelTol = 1e-6

    def test_tetgen_reader(self):
        # A unit cube split into five tetrahedra, 1-based TetGen files.
        corners = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)]
        tets = [(0, 1, 2, 4), (3, 2, 1, 7), (5, 4, 7, 1), (6, 7, 4, 2), (1, 2, 4, 7)]

        def volume(t):
            a, b, c, d = (np.array(corners[k], float) for k in t)
            return np.dot(np.cross(b - a, c - a), d - a) / 6.0

        tets = [t if volume(t) > 0 else (t[1], t[0], t[2], t[3]) for t in tets]
        with tempfile.TemporaryDirectory(prefix="translucency-plugin-") as tmp:
            base = os.path.join(tmp, "cube")
            with open(base + ".node", "w") as f:
                f.write("8 3 0 0\n")
                for i, p in enumerate(corners):
                    f.write("%d %g %g %g\n" % ((i + 1,) + p))
            with open(base + ".ele", "w") as f:
                f.write("5 4 1\n")
                for i, t in enumerate(tets):
                    f.write("%d %s %d\n" % (i + 1, " ".join(str(k + 1) for k in t), 10 + i))

            for reader in (TetGenReader(FileName=base + ".node"), OpenDataFile(base + ".ele")):
                self.assertIsNotNone(reader, "no reader for .ele files")
                self.assertEqual(reader.GetXMLName(), "TetGenReader")
                mesh = self.fetch(reader)
                self.assertEqual(mesh.GetNumberOfPoints(), 8)
                self.assertEqual(mesh.GetNumberOfCells(), 5)
                self.assertTrue(np.array_equal(cell_array(mesh, "RegionAttribute"),
                                               [10, 11, 12, 13, 14]))
                # The tets read fill the unit cube, positively oriented.
                points = vtk_to_numpy(mesh.GetPoints().GetData()).astype(float)
                cells = vtk_to_numpy(mesh.GetCells().GetConnectivityArray()).reshape(-1, 4)
                a, b, c, d = (points[cells[:, k]] for k in range(4))
                volumes = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6.0
                self.assertTrue(np.all(volumes > 0))
                self.assertAlmostEqual(float(volumes.sum()), 1.0, places=12)
                Delete(reader)

            # The read mesh goes through the rest of the chain.
            reader = TetGenReader(FileName=base + ".node")
            assign = AssignScatteringCoefficients(Input=reader)
            light = SurfaceIrradiance(Input=assign)
            solve = SolveDiffusion(Input=light)
            grid = self.fetch(solve)
            self.assertTrue(np.all(point_array(grid, "Fluence") > 0.0))
            for proxy in (solve, light, assign, reader):
                Delete(proxy)

            # Heterogeneous materials: a JSON table picked by RegionAttribute,
            # then layers by depth (Documentation/Materials.md).
            import json
            table = os.path.join(tmp, "table.json")
            presets = ["marble", "skin1", "ketchup", "apple", "potato"]
            with open(table, "w") as f:
                json.dump({"materials": [{"id": 10 + i, "preset": p}
                                         for i, p in enumerate(presets)]}, f)
            reader = TetGenReader(FileName=base + ".node")
            assign = AssignScatteringCoefficients(Input=reader, MaterialMode="Material Ids (table)",
                                                  MaterialTableFileName=table)
            mesh = self.fetch(assign)
            scattering = cell_array(mesh, "ReducedScatteringCoefficient")
            for c, region in enumerate(cell_array(mesh, "RegionAttribute")):
                uniform = AssignScatteringCoefficients(Input=reader,
                                                       MaterialName=presets[int(region) - 10])
                expected = cell_array(self.fetch(uniform), "ReducedScatteringCoefficient")[0]
                self.assertTrue(np.array_equal(scattering[c], expected))
                Delete(uniform)
            assign.MaterialMode = "Layers by Depth"
            assign.Layers = ["0.3", "skin1", "1", "marble"]
            mesh = self.fetch(assign)
            # The four corner tets have their centroid 0.25 mm deep, the
            # central tet (the last) 0.5 mm.
            self.assertEqual(assign.GetProperty("Layers").GetNumberOfElements(), 4)
            scattering = cell_array(mesh, "ReducedScatteringCoefficient")
            self.assertTrue(np.array_equal(scattering[:4], [[0.74, 0.88, 1.01]] * 4))
            self.assertTrue(np.array_equal(scattering[4], [2.19, 2.62, 3.00]))
            # Veins without turbulence: planar bands across z, weights in [0, 1].
            assign.MaterialMode = "Marble Veins"
            assign.VeinDirection = [0, 0, 1]
            assign.VeinTurbulence = 0.0
            assign.VeinSharpness = 1.0
            assign.VeinFrequency = 0.5
            mesh = self.fetch(assign)
            centroid_z = []
            for c in range(5):
                ids = mesh.GetCell(c).GetPointIds()
                centroid_z.append(sum(mesh.GetPoint(ids.GetId(k))[2] for k in range(4)) / 4)
            marble, chicken1 = np.array([2.19, 2.62, 3.00]), np.array([0.15, 0.21, 0.38])
            for c, zc in enumerate(centroid_z):
                w = 1 - abs(np.sin(2 * np.pi * 0.5 * zc))
                self.assertTrue(np.allclose(cell_array(mesh, "ReducedScatteringCoefficient")[c],
                                            (1 - w) * marble + w * chicken1, rtol=1e-12))
            for proxy in (assign, reader):
                Delete(proxy)



    def test_surface_reader(self):
        bunny = os.path.join(os.environ.get("TRANSLUCENCY_SOURCE_DIR",
                                            os.path.join(os.path.dirname(__file__), "..", "..")),
                             "Data", "bunny.ply")
        reader = TranslucencySurfaceReader(FileName=bunny)
        ours = self.fetch(reader)
        self.assertEqual(ours.GetNumberOfPoints(), 1839)
        self.assertEqual(ours.GetNumberOfPolys(), 3674)
        opened = OpenDataFile(bunny)
        self.assertIsNotNone(opened, "no reader for .ply files with the plugin loaded")
        theirs = self.fetch(opened)
        self.assertTrue(np.array_equal(vtk_to_numpy(ours.GetPoints().GetData()),
                                       vtk_to_numpy(theirs.GetPoints().GetData())))
        # The surface goes through the chain.
        tetra = Tetrahedralize(Input=reader, TargetNumberOfTets=5000)
        self.assertGreater(self.fetch(tetra).GetNumberOfCells(), 1000)
        Delete(tetra)
        Delete(opened)
        Delete(reader)
        with tempfile.TemporaryDirectory(prefix="translucency-plugin-") as tmp:
            bad = os.path.join(tmp, "bad.ply")
            with open(bunny, "rb") as f:
                data = f.read()
            with open(bad, "wb") as f:
                f.write(data.replace(b"element vertex 1839", b"element vertex 900000000"))
            reader = TranslucencySurfaceReader(FileName=bad)
            vtkObject.GlobalWarningDisplayOff()
            try:
                self.assertEqual(self.fetch(reader).GetNumberOfPoints(), 0)
            finally:
                vtkObject.GlobalWarningDisplayOn()
            Delete(reader)

if __name__ == "__main__":
    result = unittest.main(argv=[sys.argv[0]], exit=False, verbosity=2).result
    sys.exit(0 if result.wasSuccessful() else 1)
