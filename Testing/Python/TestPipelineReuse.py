#!/usr/bin/env python3
"""No needless re-execution in the filter chain (issue 31, Documentation/Pipeline.md,
"What re-executes after an edit").

How to run (from a build tree; ctest sets the variables itself):

    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestPipelineReuse.py

A marble sphere -> Surface Irradiance (a directional, a coloured directional,
a point, a coloured point and a spot light, the uniform light with 8 occlusion
samples) -> Paint (a stroke outside the object) -> Solve Diffusion
(multigrid-agg, RelTol 1e-10). Checked:
1. Turning one light of each kind recomputes that light only (and not the
   uniform light), and the Irradiance equals a new filter's (no cache) to
   1e-12.
2. The relight does not repaint (Paint re-uses its arrays, no per-tet work),
   the solve rebuilds the right-hand side only ("right-hand side") and keeps
   the multigrid hierarchy ("kept"), and the fluence equals a new filter's
   solve of the relit input (rtol 1e-7).
3. A no-op paint (the paint filter modified, the same values painted) does
   not re-run the solve's assembly ("incremental", 0 changed tets, set-up
   "kept"); a real stroke updates the touched rows ("incremental", "rows").
4. Another uniform-light sample count recomputes the uniform term only.
6. Under ParaView's executive (vtkPVCompositeDataPipeline), every double
   point and cell array of each filter's output (Surface Irradiance, Paint,
   Solve Diffusion, Outgoing Radiance) carries VTK's range cache when the
   filter returns (vtkTranslucencyRanges.h: ParaView reads it after every
   execution), and its cached ranges, finite ranges and magnitude ranges
   equal VTK's own computation on a fresh copy bit for bit; under VTK's own
   executive no range is cached (the output, and a file written from it,
   as before).
5. Under the default collimated model (extended-moments for the directional
   lights: the beam's volume source), a paint casts no ray: the solve's
   source re-integrates the painted tets only ("loads"; a no-op paint:
   "kept"), a turned light casts new rays ("full"), and each fluence equals
   a new filter's solve of the same input (rtol 1e-7).

Exits non-zero on failure (unittest).
"""

import math
import unittest

import numpy as np

import translucency
from TestPaint import marble_mesh
from TestPipeline import Messages, array
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkAbstractArray, vtkDoubleArray
from vtkmodules.vtkCommonDataModel import vtkUnstructuredGrid
from vtkmodules.vtkCommonExecutionModel import vtkCompositeDataPipeline
from paraview.modules.vtkPVVTKExtensionsCore import vtkPVCompositeDataPipeline


def run(*algorithms):
    """Update the last algorithm; fail on any error or warning."""
    messages = Messages(*algorithms)
    try:
        algorithms[-1].Update()
    finally:
        messages.remove()
    assert not messages.errors + messages.pipeline_errors + messages.warnings, (
        messages.errors + messages.warnings)


def turned(v, degrees):
    """v rotated about the z axis."""
    t = math.radians(degrees)
    return (math.cos(t) * v[0] - math.sin(t) * v[1], math.sin(t) * v[0] + math.cos(t) * v[1], v[2])


class Lights:
    """The light set, each kind with a turn of its own."""

    def __init__(self):
        self.directional = (0.3, -1.0, -0.5)
        self.coloured = (-0.5, -0.2, -1.0)
        self.point = (9.0, 4.0, 8.0)
        self.coloured_point = (-8.0, 6.0, 3.0)
        self.spot = (0.5, 9.0, 2.0)

    def apply(self, f):
        f.RemoveAllDirectionalLights()
        f.RemoveAllPointLights()
        f.RemoveAllSpotLights()
        f.RemoveAllColouredDirectionalLights()
        f.RemoveAllColouredPointLights()
        f.AddDirectionalLight(*self.directional, 1.0)
        f.AddColouredDirectionalLight(*self.coloured, 0.8, 0.5, 0.2)
        f.AddPointLight(*self.point, 60.0)
        f.AddColouredPointLight(*self.coloured_point, 30.0, 50.0, 70.0)
        # A spot above the sphere aimed at its centre, 30-degree cone.
        axis = tuple(-c for c in self.spot)
        f.AddSpotLight(*self.spot, *axis, 30.0, 2.0, 90.0, 60.0, 40.0)
        f.SetUniformLightIrradiance(0.1)


def new_solver():
    solve = translucency.vtkSolveDiffusion()
    solve.SetRelTol(1e-10)
    solve.SetMaxIter(20000)
    solve.SetLinearSolver("multigrid-agg")
    return solve


class PipelineReuseTest(unittest.TestCase):

    def setUp(self):
        self.grid = marble_mesh(3000)
        self.light_set = Lights()
        self.lights = translucency.vtkSurfaceIrradiance()
        self.lights.SetInputData(self.grid)
        # The surface model: its relight and paint reuse the assembly (the
        # default by light kind, extended-moments, assembles in full).
        self.lights.SetCollimatedModel(self.lights.COLLIMATED_SURFACE)
        self.lights.SetUniformLightSamples(8)
        self.light_set.apply(self.lights)
        self.paint = translucency.vtkPaintScatteringCoefficients()
        self.paint.SetInputConnection(self.lights.GetOutputPort())
        self.paint.AddStrokePoint(40.0, 0.0, 0.0)  # outside the sphere of radius 5
        self.paint.SetWidth(0.5)
        self.paint.SetTargetAbsorptionCoefficient(0.02, 0.05, 0.1)
        self.paint.SetTargetReducedScatteringCoefficient(1.5, 1.8, 2.0)
        self.solve = new_solver()
        self.solve.SetInputConnection(self.paint.GetOutputPort())
        run(self.lights, self.paint, self.solve)
        self.assertEqual(self.lights.GetNumberOfLightsComputed(), 5)
        self.assertTrue(self.lights.GetUniformComputed())
        self.assertEqual(self.solve.GetLastAssembly(), "full")
        self.assertEqual(self.solve.GetLastLinearSetup(), "rebuilt")

    def fresh_irradiance(self):
        f = translucency.vtkSurfaceIrradiance()
        f.SetInputData(self.grid)
        f.SetCollimatedModel(f.COLLIMATED_SURFACE)
        f.SetUniformLightSamples(self.lights.GetUniformLightSamples())
        self.light_set.apply(f)
        run(f)
        self.assertEqual(f.GetNumberOfLightsComputed(), 5)
        return array(f.GetOutput(), "Irradiance")

    def reference_fluence(self):
        copy = vtkUnstructuredGrid()
        copy.ShallowCopy(self.paint.GetOutput())
        solve = new_solver()
        solve.SetInputData(copy)
        run(solve)
        return array(solve.GetOutput(), "Fluence")

    def assert_irradiance_is_fresh(self):
        q = array(self.lights.GetOutput(), "Irradiance")
        ref = self.fresh_irradiance()
        self.assertLessEqual(np.max(np.abs(q - ref)), 1e-12 * np.max(np.abs(ref)))

    def test_relight_recomputes_one_light_and_keeps_the_rest(self):
        paintings = self.paint.GetNumberOfPaintings()
        self.assertEqual(paintings, 1)
        before = array(self.lights.GetOutput(), "Irradiance").copy()
        for kind in ("directional", "coloured", "point", "coloured_point", "spot"):
            with self.subTest(kind=kind):
                setattr(self.light_set, kind, turned(getattr(self.light_set, kind), 15.0))
                self.light_set.apply(self.lights)
                run(self.lights, self.paint, self.solve)
                self.assertEqual(self.lights.GetNumberOfLightsComputed(), 1)
                self.assertFalse(self.lights.GetUniformComputed())
                self.assert_irradiance_is_fresh()
                # Paint carried the relit irradiance through without painting.
                self.assertTrue(self.paint.GetLastExecutionReused())
                self.assertEqual(self.paint.GetNumberOfPaintings(), paintings)
                np.testing.assert_array_equal(array(self.paint.GetOutput(), "Irradiance"),
                                              array(self.lights.GetOutput(), "Irradiance"))
                # The solve: right-hand side only, the hierarchy kept.
                self.assertEqual(self.solve.GetLastAssembly(), "right-hand side")
                self.assertEqual(self.solve.GetLastLinearSetup(), "kept")
                np.testing.assert_allclose(array(self.solve.GetOutput(), "Fluence"),
                                           self.reference_fluence(), rtol=1e-7)
        self.assertGreater(np.max(np.abs(array(self.lights.GetOutput(), "Irradiance") - before)),
                           1e-3 * np.max(before))

    def test_no_op_paint_keeps_the_assembly(self):
        # The paint filter modified without a change of what it paints.
        self.paint.Modified()
        run(self.lights, self.paint, self.solve)
        self.assertFalse(self.paint.GetLastExecutionReused())
        self.assertEqual(self.paint.GetNumberOfPaintings(), 2)
        self.assertEqual(self.solve.GetLastAssembly(), "incremental")
        self.assertEqual(self.solve.GetNumberOfChangedTets(), 0)
        self.assertEqual(self.solve.GetLastLinearSetup(), "kept")
        # A real stroke: the touched rows.
        self.paint.RemoveAllStrokePoints()
        self.paint.AddStrokePoint(0.0, 5.0, 0.0)
        self.paint.SetWidth(0.2)  # about 0.5 % of the tets (incremental below 5 %)
        run(self.lights, self.paint, self.solve)
        painted = self.paint.GetOutput().GetFieldData().GetArray("PaintedCellIds")
        self.assertGreater(painted.GetNumberOfTuples(), 0)
        self.assertEqual(self.solve.GetLastAssembly(), "incremental")
        self.assertEqual(self.solve.GetNumberOfChangedTets(), painted.GetNumberOfTuples())
        self.assertEqual(self.solve.GetLastLinearSetup(), "rows")
        np.testing.assert_allclose(array(self.solve.GetOutput(), "Fluence"),
                                   self.reference_fluence(), rtol=1e-7)
        # A relight after the stroke: the painted arrays are carried through.
        self.light_set.directional = turned(self.light_set.directional, 15.0)
        self.light_set.apply(self.lights)
        run(self.lights, self.paint, self.solve)
        self.assertTrue(self.paint.GetLastExecutionReused())
        self.assertEqual(self.paint.GetNumberOfPaintings(), 3)
        self.assertEqual(self.solve.GetLastAssembly(), "right-hand side")
        self.assertEqual(self.solve.GetLastLinearSetup(), "kept")

    def test_uniform_samples_recompute_the_uniform_term_only(self):
        self.lights.SetUniformLightSamples(16)
        run(self.lights, self.paint, self.solve)
        self.assertEqual(self.lights.GetNumberOfLightsComputed(), 0)
        self.assertTrue(self.lights.GetUniformComputed())
        self.assert_irradiance_is_fresh()



class DefaultModelPaintTest(unittest.TestCase):
    """Item 5: the extended source kept across paints."""

    def setUp(self):
        self.grid = marble_mesh(3000)
        self.lights = translucency.vtkSurfaceIrradiance()
        self.lights.SetInputData(self.grid)
        self.lights.AddDirectionalLight(0.3, -1.0, -0.5, 1.0)
        self.lights.AddColouredDirectionalLight(-0.5, -0.2, -1.0, 0.8, 0.5, 0.2)
        self.lights.SetUniformLightIrradiance(0.1)
        self.lights.SetUniformLightSamples(8)
        self.paint = translucency.vtkPaintScatteringCoefficients()
        self.paint.SetInputConnection(self.lights.GetOutputPort())
        self.paint.AddStrokePoint(40.0, 0.0, 0.0)  # outside the sphere of radius 5
        self.paint.SetWidth(0.5)
        self.paint.SetTargetAbsorptionCoefficient(0.02, 0.05, 0.1)
        self.paint.SetTargetReducedScatteringCoefficient(1.5, 1.8, 2.0)
        self.solve = new_solver()
        self.solve.SetInputConnection(self.paint.GetOutputPort())
        run(self.lights, self.paint, self.solve)
        self.assertEqual(self.solve.GetSolvedCollimatedModel(), 2)  # extended-moments
        self.assertEqual(self.solve.GetLastCollimatedUpdate(), "full")

    def assert_fluence_is_fresh(self):
        copy = vtkUnstructuredGrid()
        copy.ShallowCopy(self.paint.GetOutput())
        solve = new_solver()
        solve.SetInputData(copy)
        run(solve)
        self.assertEqual(solve.GetLastCollimatedUpdate(), "full")
        np.testing.assert_allclose(array(self.solve.GetOutput(), "Fluence"),
                                   array(solve.GetOutput(), "Fluence"), rtol=1e-7)
        np.testing.assert_array_equal(array(self.solve.GetOutput(), "CollimatedFluence"),
                                      array(solve.GetOutput(), "CollimatedFluence"))

    def test_paint_casts_no_ray(self):
        self.paint.Modified()  # the same values painted
        run(self.lights, self.paint, self.solve)
        self.assertEqual(self.solve.GetLastCollimatedUpdate(), "kept")
        for x, y, z in ((0.0, 0.0, 0.0), (0.0, 5.0, 0.0)):  # inside; through the lit top
            with self.subTest(stroke=(x, y, z)):
                self.paint.RemoveAllStrokePoints()
                self.paint.AddStrokePoint(x, y, z)
                self.paint.SetWidth(1.0)
                run(self.lights, self.paint, self.solve)
                painted = self.paint.GetOutput().GetFieldData().GetArray("PaintedCellIds")
                self.assertGreater(painted.GetNumberOfTuples(), 0)
                self.assertEqual(self.solve.GetLastCollimatedUpdate(), "loads")
                self.assert_fluence_is_fresh()
        self.lights.RemoveAllDirectionalLights()
        self.lights.AddDirectionalLight(*turned((0.3, -1.0, -0.5), 15.0), 1.0)
        run(self.lights, self.paint, self.solve)
        self.assertEqual(self.solve.GetLastCollimatedUpdate(), "full")
        self.assert_fluence_is_fresh()


class ArrayRangesTest(unittest.TestCase):
    """Item 6: the range cache of the filters' outputs."""

    def chain(self, executive):
        grid = marble_mesh(3000)
        lights = translucency.vtkSurfaceIrradiance()
        paint = translucency.vtkPaintScatteringCoefficients()
        solve = new_solver()
        radiance = translucency.vtkOutgoingRadiance()
        filters = (("irradiance", lights), ("paint", paint), ("solve", solve),
                   ("radiance", radiance))
        for _, f in filters:
            f.SetExecutive(executive())  # before the connections, which it holds
        lights.SetInputData(grid)
        lights.AddDirectionalLight(0.3, -1.0, -0.5, 1.0)
        lights.SetUniformLightSamples(8)
        paint.SetInputConnection(lights.GetOutputPort())
        paint.AddStrokePoint(0.0, 5.0, 0.0)
        paint.SetWidth(1.0)
        paint.SetTargetAbsorptionCoefficient(0.02, 0.05, 0.1)
        paint.SetTargetReducedScatteringCoefficient(1.5, 1.8, 2.0)
        solve.SetInputConnection(paint.GetOutputPort())
        radiance.SetInputConnection(solve.GetOutputPort())
        run(lights, paint, solve, radiance)
        return filters

    def test_vtk_executive_caches_nothing(self):
        for name, f in self.chain(vtkCompositeDataPipeline):
            irradiance = f.GetOutput().GetPointData().GetArray("Irradiance")
            self.assertFalse(irradiance.GetInformation().Has(vtkAbstractArray.PER_COMPONENT()),
                             name)

    def test_cached_ranges_equal_vtk(self):
        checked = 0
        for name, f in self.chain(vtkPVCompositeDataPipeline):
            data = f.GetOutput()
            for attributes in (data.GetPointData(), data.GetCellData()):
                for a in range(attributes.GetNumberOfArrays()):
                    array = attributes.GetArray(a)
                    if not isinstance(array, vtkDoubleArray) or array.GetNumberOfTuples() == 0:
                        continue
                    label = "%s: %s" % (name, array.GetName())
                    with self.subTest(array=label):
                        self.assertTrue(array.GetInformation().Has(vtkAbstractArray.PER_COMPONENT()),
                                        label + " has no cached range")
                        fresh = numpy_to_vtk(vtk_to_numpy(array).copy(), deep=1)
                        components = array.GetNumberOfComponents()
                        for k in list(range(components)) + ([-1] if components > 1 else []):
                            self.assertEqual(array.GetRange(k), fresh.GetRange(k), (label, k))
                            self.assertEqual(array.GetFiniteRange(k), fresh.GetFiniteRange(k),
                                             (label, k))
                        checked += 1
        self.assertGreater(checked, 10)

if __name__ == "__main__":
    unittest.main(verbosity=2)
