#!/usr/bin/env python3
"""vtkDetectorReadings (the detector tables), Solve Diffusion's interactive
sources and Surface Irradiance's coloured light lists, through the VTK
filters (issue 19; Documentation/DiffuseOptics.md).

How to run (ctest does this):

    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestDetectorTable.py

1. A 20 x 20 x 6 mm slab (about 3k tets), a point source inside, two
   detectors (one a fibre): table 0 has one row per detector whose every
   value equals the filter's getters exactly (requested and surface
   position, radius, fluence and exitance R, G, B).
2. At 100 MHz the phase columns equal the phase getters; in continuous wave
   there are none.
3. With 8 time gates, table 1 has the column "Time (ns)" equal to
   TimeGateCentres and, per detector, quantity and channel, a column equal
   to the DetectorFluenceTPSF<k> / DetectorExitanceTPSF<k> field arrays.
4. An input without detectors, and a table asked of a failed solve, give an
   error naming what to do (PipelineError) and empty tables.
5. The interactive point source gives the same fluence as AddPointSource at
   the same place; the interactive pencil beam from above the top face
   gives the fluence of AddPencilBeam at its entry point; coinciding
   points, a beam that misses and a start inside the object are errors
   naming them.
6. AddColouredDirectionalLight / AddColouredPointLight give the irradiance
   of AddDirectionalLightRGB / AddPointLightRGB, and RemoveAllDirectionalLights
   leaves the coloured list alone (the panel's tables clear only their own).

Exits non-zero on failure (unittest).
"""

import unittest

import vtk  # ParaView's VTK 9.2 (python3-paraview)
from vtk.util.numpy_support import vtk_to_numpy
import numpy as np

import translucency

DETECTORS = ((5.0, 0.0, 0.0, 0.0), (-3.0, 4.0, 0.0, 1.0))  # x, y, z (mm), radius (mm)
SOURCE = (1.0, -1.0, -3.0)


def make_slab():
    box = vtk.vtkTessellatedBoxSource()
    box.SetBounds(-10, 10, -10, 10, -6, 0)
    box.SetLevel(5)
    box.QuadsOff()
    tets = translucency.vtkTetrahedralizeSurface()
    tets.SetInputConnection(box.GetOutputPort())
    tets.SetTargetNumberOfTets(3000)
    tissue = translucency.vtkAssignScatteringCoefficients()
    tissue.SetInputConnection(tets.GetOutputPort())
    tissue.SetAbsorptionCoefficient(0.02, 0.03, 0.05)
    tissue.SetReducedScatteringCoefficient(1.0, 1.1, 1.2)
    tissue.SetRefractiveIndex(1.4)
    dark = translucency.vtkSurfaceIrradiance()
    dark.SetInputConnection(tissue.GetOutputPort())
    dark.SetDefaultLights(False)
    translucency.update(dark)
    slab = vtk.vtkUnstructuredGrid()
    slab.DeepCopy(dark.GetOutput())
    return tissue, slab


def make_solve(slab, detectors=True):
    solve = translucency.vtkSolveDiffusion()
    solve.SetInputData(slab)
    solve.SetSolverByName("divergence")
    solve.SetRelTol(1e-10)
    if detectors:
        for d in DETECTORS:
            solve.AddDetector(*d)
    return solve


def column(table, name):
    array = table.GetColumnByName(name)
    if array is None:
        names = [table.GetColumnName(i) for i in range(table.GetNumberOfColumns())]
        raise AssertionError("no column %r; the table has %s" % (name, names))
    return vtk_to_numpy(array)


class DetectorTableTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.tissue, cls.slab = make_slab()

    def readings(self, solve):
        table = translucency.vtkDetectorReadings()
        table.SetInputConnection(solve.GetOutputPort())
        translucency.update(table)
        return table, table.GetOutput(0), table.GetOutput(1)

    def test_rows_equal_the_getters(self):
        solve = make_solve(self.slab)
        solve.AddPointSource(*SOURCE, 1.0, 2.0, 0.5)
        _, rows, gates = self.readings(solve)
        self.assertEqual(rows.GetNumberOfRows(), len(DETECTORS))
        self.assertEqual(gates.GetNumberOfRows(), 0)  # no time gates
        self.assertEqual(list(column(rows, "Detector")), [0, 1])
        for k, (x, y, z, radius) in enumerate(DETECTORS):
            self.assertEqual(column(rows, "RequestedX")[k], x)
            self.assertEqual(column(rows, "RequestedY")[k], y)
            self.assertEqual(column(rows, "RequestedZ")[k], z)
            self.assertEqual(column(rows, "Radius")[k], radius)
            surface = [0.0] * 3
            solve.GetDetectorSurfacePosition(k, surface)
            for axis, value in zip("XYZ", surface):
                self.assertEqual(column(rows, "Surface" + axis)[k], value)
            for c, channel in enumerate("RGB"):
                fluence = solve.GetDetectorFluence(k, c)
                exitance = solve.GetDetectorExitance(k, c)
                self.assertGreater(fluence, 0.0)
                self.assertEqual(column(rows, "Fluence" + channel)[k], fluence)
                self.assertEqual(column(rows, "Exitance" + channel)[k], exitance)
        self.assertIsNone(rows.GetColumnByName("FluencePhaseR"))  # continuous wave

    def test_phase_columns_at_a_frequency(self):
        solve = make_solve(self.slab)
        solve.AddPointSource(*SOURCE, 1.0, 1.0, 1.0)
        solve.SetModulationFrequency(100e6)
        _, rows, _ = self.readings(solve)
        self.assertEqual(rows.GetNumberOfRows(), len(DETECTORS))
        for k in range(len(DETECTORS)):
            for c, channel in enumerate("RGB"):
                self.assertEqual(column(rows, "Fluence" + channel)[k],
                                 solve.GetDetectorFluence(k, c))
                self.assertEqual(column(rows, "FluencePhase" + channel)[k],
                                 solve.GetDetectorFluencePhase(k, c))
                self.assertEqual(column(rows, "ExitancePhase" + channel)[k],
                                 solve.GetDetectorExitancePhase(k, c))
                self.assertLess(solve.GetDetectorFluencePhase(k, c), 0.0)  # lags the source

    def test_time_gate_table_equals_the_field_arrays(self):
        solve = make_solve(self.slab)
        solve.AddPointSource(*SOURCE, 1.0, 1.0, 1.0)
        solve.SetTimeGates(0.0, 2.0, 8)
        _, rows, gates = self.readings(solve)
        fd = solve.GetOutput().GetFieldData()
        self.assertEqual(gates.GetNumberOfRows(), 8)
        self.assertEqual(gates.GetNumberOfColumns(), 1 + 2 * 3 * len(DETECTORS))
        np.testing.assert_array_equal(column(gates, "Time (ns)"),
                                      vtk_to_numpy(fd.GetArray("TimeGateCentres")))
        for k in range(len(DETECTORS)):
            for quantity in ("Fluence", "Exitance"):
                field = vtk_to_numpy(fd.GetArray("Detector%sTPSF%d" % (quantity, k)))
                for c, channel in enumerate("RGB"):
                    np.testing.assert_array_equal(
                        column(gates, "Detector%d_%s%s" % (k, quantity, channel)), field[:, c])
            self.assertGreater(column(gates, "Detector%d_FluenceR" % k).max(), 0.0)
        # Table 0 holds the time integrals, as the getters.
        self.assertEqual(column(rows, "FluenceG")[1], solve.GetDetectorFluence(1, 1))

    def test_no_detectors_is_an_error(self):
        solve = make_solve(self.slab, detectors=False)
        solve.AddPointSource(*SOURCE, 1.0, 1.0, 1.0)
        with self.assertRaises(translucency.PipelineError) as caught:
            self.readings(solve)
        self.assertIn("no detector readings", str(caught.exception))
        self.assertIn("AddDetector", str(caught.exception))
        # A failed solve (source outside the object): error, empty tables.
        bad = make_solve(self.slab)
        bad.AddPointSource(50.0, 0.0, -3.0, 1.0, 1.0, 1.0)
        table = translucency.vtkDetectorReadings()
        table.SetInputConnection(bad.GetOutputPort())
        with self.assertRaises(translucency.PipelineError):
            translucency.update(table)
        self.assertEqual(table.GetOutput(0).GetNumberOfRows(), 0)
        self.assertEqual(table.GetOutput(1).GetNumberOfRows(), 0)

    def fluence(self, solve):
        translucency.update(solve)
        return vtk_to_numpy(solve.GetOutput().GetPointData().GetArray("Fluence")).copy()

    def test_interactive_point_source(self):
        listed = make_solve(self.slab, detectors=False)
        listed.AddPointSource(*SOURCE, 1.0, 2.0, 3.0)
        interactive = make_solve(self.slab, detectors=False)
        interactive.InteractivePointSourceOn()
        interactive.SetInteractivePointSourcePosition(*SOURCE)
        interactive.SetInteractivePointSourcePower(1.0, 2.0, 3.0)
        expected = self.fluence(listed)
        got = self.fluence(interactive)
        np.testing.assert_array_equal(got, expected)
        interactive.InteractivePointSourceOff()  # off: no source at all
        self.assertEqual(np.abs(self.fluence(interactive)).max(), 0.0)

    def test_interactive_pencil_beam(self):
        listed = make_solve(self.slab, detectors=False)
        listed.AddPencilBeam(2.0, 1.0, 0.0, 0.0, 0.0, -1.0, 1.0, 1.0, 1.0)
        expected = self.fluence(listed)
        for start in ((2.0, 1.0, 7.0), (2.0, 1.0, 0.0)):  # above the face, and on it
            interactive = make_solve(self.slab, detectors=False)
            interactive.InteractivePencilBeamOn()
            interactive.SetInteractivePencilBeamPoint1(*start)
            interactive.SetInteractivePencilBeamPoint2(2.0, 1.0, -3.0)
            got = self.fluence(interactive)
            entry = interactive.GetInteractivePencilBeamEntry()
            np.testing.assert_allclose(entry, (2.0, 1.0, 0.0), atol=1e-12)
            np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-12 * expected.max())

    def test_interactive_pencil_beam_errors(self):
        cases = (((0.0, 0.0, 5.0), (0.0, 0.0, 5.0), "the two points are the same"),
                 ((30.0, 0.0, 5.0), (30.0, 0.0, -5.0), "misses the object"),
                 ((0.0, 0.0, -3.0), (0.0, 0.0, -5.0), "Point 1 is inside the object"))
        for point1, point2, message in cases:
            solve = make_solve(self.slab, detectors=False)
            solve.InteractivePencilBeamOn()
            solve.SetInteractivePencilBeamPoint1(*point1)
            solve.SetInteractivePencilBeamPoint2(*point2)
            with self.assertRaises(translucency.PipelineError) as caught:
                translucency.update(solve)
            self.assertIn("interactive pencil beam", str(caught.exception))
            self.assertIn(message, str(caught.exception))

    def irradiance(self, configure):
        lights = translucency.vtkSurfaceIrradiance()
        lights.SetInputConnection(self.tissue.GetOutputPort())
        lights.SetDefaultLights(False)
        configure(lights)
        translucency.update(lights)
        return vtk_to_numpy(lights.GetOutput().GetPointData().GetArray("Irradiance")).copy()

    def test_coloured_light_lists(self):
        rgb = self.irradiance(lambda f: (f.AddDirectionalLightRGB(0.2, 0.1, -1.0, 1.0, 2.0, 3.0),
                                         f.AddPointLightRGB(3.0, 2.0, 20.0, 50.0, 0.0, 10.0)))
        coloured = self.irradiance(
            lambda f: (f.AddColouredDirectionalLight(0.2, 0.1, -1.0, 1.0, 2.0, 3.0),
                       f.AddColouredPointLight(3.0, 2.0, 20.0, 50.0, 0.0, 10.0)))
        self.assertGreater(rgb[:, 2].max(), 0.0)
        np.testing.assert_array_equal(coloured, rgb)
        kept = self.irradiance(
            lambda f: (f.AddColouredDirectionalLight(0.2, 0.1, -1.0, 1.0, 2.0, 3.0),
                       f.AddColouredPointLight(3.0, 2.0, 20.0, 50.0, 0.0, 10.0),
                       f.AddDirectionalLight(1.0, 0.0, 0.0, 5.0),
                       f.RemoveAllDirectionalLights(), f.RemoveAllPointLights()))
        np.testing.assert_array_equal(kept, rgb)
        cleared = self.irradiance(
            lambda f: (f.AddColouredDirectionalLight(0.2, 0.1, -1.0, 1.0, 2.0, 3.0),
                       f.RemoveAllColouredDirectionalLights()))
        self.assertEqual(np.abs(cleared).max(), 0.0)


if __name__ == "__main__":
    unittest.main(verbosity=2)
