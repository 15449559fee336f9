"""The plugin's diffuse-optics panel (issue 19), run by pvpython: Solve
Diffusion's interactive point source and pencil beam (the properties of the
handle and line widgets), the Detector Readings proxy, and the coloured and
spot light tables of Surface Irradiance.

How to run (ctest does this):

    pvpython --force-offscreen-rendering TestDetectorPlugin.py <build>/lib/paraview-plugins/Translucency/Translucency.so

1. Box (20 x 20 x 6 mm) -> Triangulate -> Tetrahedralize Surface -> Assign
   Scattering Coefficients -> Surface Irradiance (no light) -> Solve
   Diffusion with InteractivePointSource on and two detectors on the top
   face -> Detector Readings. The widget properties start from the data
   bounds (the point source at the centre; the beam from the top centre
   towards the centre).
2. The point source at the centre: the detector above it reads more than
   the far one, and the brightest vertex is the one next to the source;
   moved under the far detector (the handle widget's WorldPosition), the
   order of the two readings turns round.
3. The interactive pencil beam with its default line: the brightest vertex
   is just below the top centre; Point 2 = Point 1 is an error and leaves
   an empty output.
4. Detector Readings: two rows, equal to the DetectorFluence field array;
   without detectors an empty table.
5. Surface Irradiance's ColouredDirectionalLights and SpotLights tables:
   a red-only spot and a coloured directional light give the expected
   channel ratios.
6. quadgraph and grid take the interactive point source and a listed pencil
   beam: the brightest vertex is next to the source, the detectors' order
   follows it.
7. The interactive detector (a handle widget): default at the top centre
   of the bounds; a third row in Detector Readings, read at the surface
   point closest to the handle (above or below the face), equal to the
   listed detector at that point (1e-12), changed when moved or given a
   fibre radius; a negative radius is an error.
8. Time Steps Per Gate and Time Snapshots: FluenceGate<g> for the gates
   asked; 4 steps per gate give the automatic choice's TPSF, 1 step per
   gate changes it (measured: at most 34 %, in the first gates; bound 50 %).

Exits non-zero on failure (unittest). No rendering.
"""

import os
import sys
import unittest

from paraview.simple import *  # noqa: F401,F403
from paraview import servermanager

if len(sys.argv) < 2 or not os.path.isfile(sys.argv[1]):
    sys.exit("usage: pvpython --force-offscreen-rendering TestDetectorPlugin.py <plugin>")
LoadPlugin(sys.argv[1], ns=globals())
Tetrahedralize = TetrahedralizeSurface

from vtkmodules.util.numpy_support import vtk_to_numpy  # noqa: E402
import numpy as np  # noqa: E402

NEAR = [2.0, 0.0, 3.0, 0.0]   # x, y, z (mm), radius: above the centre
FAR = [8.0, 0.0, 3.0, 0.0]    # near the +x edge of the top face


class DetectorPluginTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.box = Box(XLength=20.0, YLength=20.0, ZLength=6.0)
        cls.triangles = Triangulate(Input=cls.box)
        cls.tetra = Tetrahedralize(Input=cls.triangles, TargetNumberOfTets=4000)
        cls.assign = AssignScatteringCoefficients(Input=cls.tetra)
        cls.dark = SurfaceIrradiance(Input=cls.assign, DirectionalLights=[],
                                     UniformLightIrradiance=0.0, DefaultLights=0)
        # As in the GUI (Apply before the next filter): the widget properties'
        # bounds domains read the input's bounds when the proxy is created.
        cls.dark.UpdatePipeline()
        cls.solve = SolveDiffusion(Input=cls.dark, Detectors=NEAR + FAR)
        cls.table = DetectorReadings(Input=cls.solve)

    def fetch(self, proxy, port=0):
        proxy.UpdatePipeline()
        return servermanager.Fetch(proxy, idx=port)

    def brightest_point(self):
        data = self.fetch(self.solve)
        fluence = vtk_to_numpy(data.GetPointData().GetArray("Fluence"))[:, 0]
        points = vtk_to_numpy(data.GetPoints().GetData())
        return points[int(np.argmax(fluence))], data

    def readings(self):
        table = self.fetch(self.table)
        self.assertEqual(table.GetNumberOfRows(), 2)
        return vtk_to_numpy(table.GetColumnByName("FluenceR")).copy(), table

    def test_1_widget_properties_start_from_the_bounds(self):
        self.assertEqual(self.solve.InteractivePointSource, 0)
        self.assertEqual(self.solve.InteractivePencilBeam, 0)
        np.testing.assert_allclose(list(self.solve.InteractivePointSourcePosition), [0, 0, 0],
                                   atol=1e-9)
        np.testing.assert_allclose(list(self.solve.InteractivePencilBeamPoint1), [0, 0, 3],
                                   atol=1e-9)
        np.testing.assert_allclose(list(self.solve.InteractivePencilBeamPoint2), [0, 0, 0],
                                   atol=1e-9)

    def test_2_point_source_moves_the_fluence(self):
        self.solve.InteractivePencilBeam = 0
        self.solve.InteractivePointSource = 1
        self.solve.InteractivePointSourcePosition = [0.0, 0.0, 0.0]
        self.solve.InteractivePointSourcePower = [1.0, 1.0, 1.0]
        brightest, data = self.brightest_point()
        self.assertLess(np.linalg.norm(brightest), 2.5)
        fluence, table = self.readings()
        self.assertGreater(fluence[0], 2.0 * fluence[1])
        field = vtk_to_numpy(data.GetFieldData().GetArray("DetectorFluence"))
        np.testing.assert_array_equal(fluence, field[:, 0])
        # The handle moved under the far detector.
        self.solve.InteractivePointSourcePosition = [8.0, 0.0, 1.5]
        brightest, _ = self.brightest_point()
        self.assertLess(np.linalg.norm(brightest - [8.0, 0.0, 1.5]), 2.5)
        fluence, _ = self.readings()
        self.assertGreater(fluence[1], 2.0 * fluence[0])
        self.solve.InteractivePointSource = 0

    def test_3_pencil_beam_from_the_line_widget(self):
        self.solve.InteractivePointSource = 0
        self.solve.InteractivePencilBeam = 1
        self.solve.InteractivePencilBeamPoint1 = [0.0, 0.0, 3.0]
        self.solve.InteractivePencilBeamPoint2 = [0.0, 0.0, 0.0]
        brightest, data = self.brightest_point()
        self.assertLess(np.linalg.norm(brightest[:2]), 2.5)
        self.assertGreater(brightest[2], 1.5)  # near the entry on the top face
        fluence, _ = self.readings()
        self.assertGreater(fluence[0], fluence[1])
        # A zero-length line: an error and an empty output.
        self.solve.InteractivePencilBeamPoint2 = [0.0, 0.0, 3.0]
        failed = self.fetch(self.solve)
        self.assertEqual(failed.GetNumberOfPoints(), 0)
        self.solve.InteractivePencilBeamPoint2 = [0.0, 0.0, 0.0]
        self.assertGreater(self.fetch(self.solve).GetNumberOfPoints(), 0)
        self.solve.InteractivePencilBeam = 0

    def test_4_no_detectors_gives_an_empty_table(self):
        solve = SolveDiffusion(Input=self.dark, InteractivePointSource=1)
        table = DetectorReadings(Input=solve)
        self.assertEqual(self.fetch(table).GetNumberOfRows(), 0)
        self.assertEqual(self.fetch(table, 1).GetNumberOfRows(), 0)
        Delete(table)
        Delete(solve)

    def test_6_sources_with_quadgraph_and_grid(self):
        # Interior sources with every solver (issue 19): the interactive
        # point source, then a listed pencil beam, with quadgraph and grid.
        for solver in ("quadgraph", "grid"):
            solve = SolveDiffusion(Input=self.dark, Solver=solver, Detectors=NEAR + FAR,
                                   InteractivePointSource=1,
                                   InteractivePointSourcePosition=[8.0, 0.0, 1.5])
            data = self.fetch(solve)
            self.assertGreater(data.GetNumberOfPoints(), 0, solver)
            fluence = vtk_to_numpy(data.GetPointData().GetArray("Fluence"))[:, 0]
            points = vtk_to_numpy(data.GetPoints().GetData())
            brightest = points[int(np.argmax(fluence))]
            self.assertLess(np.linalg.norm(brightest - [8.0, 0.0, 1.5]), 2.5, solver)
            readings = vtk_to_numpy(data.GetFieldData().GetArray("DetectorFluence"))[:, 0]
            self.assertGreater(readings[1], 2.0 * readings[0], solver)
            solve.InteractivePointSource = 0
            solve.PencilBeams = [0.0, 0.0, 3.0, 0.0, 0.0, -1.0, 1.0, 1.0, 1.0]
            data = self.fetch(solve)
            fluence = vtk_to_numpy(data.GetPointData().GetArray("Fluence"))[:, 0]
            points = vtk_to_numpy(data.GetPoints().GetData())
            brightest = points[int(np.argmax(fluence))]
            self.assertLess(np.linalg.norm(brightest[:2]), 2.5, solver)
            readings = vtk_to_numpy(data.GetFieldData().GetArray("DetectorFluence"))[:, 0]
            self.assertGreater(readings[0], readings[1], solver)
            Delete(solve)

    def test_5_coloured_and_spot_light_tables(self):
        lights = SurfaceIrradiance(Input=self.assign, DirectionalLights=[],
                                   UniformLightIrradiance=0.0, DefaultLights=0, Shadows=0,
                                   SpotLights=[0, 0, 20, 0, 0, -1, 30, 1, 100, 0, 0])
        q = vtk_to_numpy(self.fetch(lights).GetPointData().GetArray("Irradiance"))
        self.assertGreater(q[:, 0].max(), 0.0)
        self.assertEqual(np.abs(q[:, 1:]).max(), 0.0)  # a red spot
        lights.SpotLights = []
        lights.ColouredDirectionalLights = [0, 0, -1, 1.0, 0.5, 0.0]
        q = vtk_to_numpy(self.fetch(lights).GetPointData().GetArray("Irradiance"))
        top = q[:, 0] > 0
        self.assertTrue(top.any())
        np.testing.assert_allclose(q[top, 1] / q[top, 0], 0.5, rtol=1e-12)
        self.assertEqual(np.abs(q[:, 2]).max(), 0.0)
        # The grey table's clean command leaves the coloured rows alone.
        lights.DirectionalLights = [1, 0, 0, 0.0]
        lights.DirectionalLights = []
        q2 = vtk_to_numpy(self.fetch(lights).GetPointData().GetArray("Irradiance"))
        np.testing.assert_array_equal(q2, q)
        Delete(lights)

    def test_7_interactive_detector_on_a_handle(self):
        """The handle widget's detector reads at the closest surface point,
        after the listed detectors (the table's last row): moved, its reading
        changes; over a listed detector's position it reads what that detector
        reads."""
        solve = SolveDiffusion(Input=self.dark, Detectors=NEAR + FAR, InteractivePointSource=1,
                               InteractivePointSourcePosition=[0.0, 0.0, 0.0])
        table = DetectorReadings(Input=solve)
        self.assertEqual(solve.InteractiveDetector, 0)
        np.testing.assert_allclose(list(solve.InteractiveDetectorPosition), [0, 0, 3],
                                   atol=1e-9)  # the top centre of the bounds
        self.assertEqual(self.fetch(table).GetNumberOfRows(), 2)
        solve.InteractiveDetector = 1
        # 1.5 mm above NEAR: projected onto the top face, where NEAR reads.
        solve.InteractiveDetectorPosition = [NEAR[0], NEAR[1], NEAR[2] + 1.5]
        rows = self.fetch(table)
        self.assertEqual(rows.GetNumberOfRows(), 3)
        column = lambda name: vtk_to_numpy(rows.GetColumnByName(name)).copy()  # noqa: E731
        np.testing.assert_allclose([column(a)[2] for a in ("SurfaceX", "SurfaceY", "SurfaceZ")],
                                   NEAR[:3], atol=1e-9)
        self.assertAlmostEqual(column("RequestedZ")[2], NEAR[2] + 1.5, places=12)
        for name in ("FluenceR", "FluenceG", "ExitanceB"):
            self.assertAlmostEqual(column(name)[2] / column(name)[0], 1.0, places=12, msg=name)
        near = column("FluenceR")[2]
        # Moved (from inside the object, below FAR): it reads what FAR reads.
        solve.InteractiveDetectorPosition = [FAR[0], FAR[1], FAR[2] - 0.5]
        rows = self.fetch(table)
        self.assertEqual(rows.GetNumberOfRows(), 3)
        column = lambda name: vtk_to_numpy(rows.GetColumnByName(name)).copy()  # noqa: E731
        self.assertLess(column("FluenceR")[2], 0.5 * near)
        self.assertAlmostEqual(column("FluenceR")[2] / column("FluenceR")[1], 1.0, places=12)
        # A fibre radius changes the reading; a negative one is an error.
        solve.InteractiveDetectorRadius = 2.0
        rows = self.fetch(table)
        column = lambda name: vtk_to_numpy(rows.GetColumnByName(name)).copy()  # noqa: E731
        self.assertNotAlmostEqual(column("FluenceR")[2] / column("FluenceR")[1], 1.0, places=6)
        self.assertAlmostEqual(column("Radius")[2], 2.0, places=12)
        solve.InteractiveDetectorRadius = -1.0
        self.assertEqual(self.fetch(solve).GetNumberOfPoints(), 0)
        solve.InteractiveDetector = 0
        solve.InteractiveDetectorRadius = 0.0
        self.assertEqual(self.fetch(table).GetNumberOfRows(), 2)
        Delete(table)
        Delete(solve)

    def test_8_time_steps_and_snapshots(self):
        """The panel's TimeStepsPerGate and TimeSnapshots reach the filter:
        the snapshots are the point arrays FluenceGate<g>, and a different
        step count changes the TPSF (the time discretisation)."""
        solve = SolveDiffusion(Input=self.dark, Detectors=NEAR, InteractivePointSource=1,
                               InteractivePointSourcePosition=[0.0, 0.0, 0.0],
                               TimeGates=[0.0, 0.5, 10], TimeSnapshots=[3, 7])
        data = self.fetch(solve)
        self.assertIsNotNone(data.GetPointData().GetArray("FluenceGate3"))
        self.assertIsNotNone(data.GetPointData().GetArray("FluenceGate7"))
        self.assertIsNone(data.GetPointData().GetArray("FluenceGate0"))
        automatic = vtk_to_numpy(data.GetFieldData().GetArray("DetectorFluenceTPSF0")).copy()
        solve.TimeStepsPerGate = 4  # what automatic chooses for this material
        four = vtk_to_numpy(self.fetch(solve).GetFieldData().GetArray("DetectorFluenceTPSF0"))
        np.testing.assert_allclose(four, automatic, rtol=1e-9, atol=0.0)
        solve.TimeStepsPerGate = 1
        solve.TimeSnapshots = []
        data = self.fetch(solve)
        self.assertIsNone(data.GetPointData().GetArray("FluenceGate3"))
        coarse = vtk_to_numpy(data.GetFieldData().GetArray("DetectorFluenceTPSF0"))
        self.assertGreater(np.abs(coarse - automatic).max(), 1e-6 * np.abs(automatic).max())
        # Coarser, not different in kind (measured: 34 % apart at most, in the first gates).
        np.testing.assert_allclose(coarse, automatic, rtol=0.5, atol=1e-3 * automatic.max())
        Delete(solve)


if __name__ == "__main__":
    result = unittest.main(argv=[sys.argv[0]], exit=False, verbosity=2).result
    sys.exit(0 if result.wasSuccessful() else 1)
