"""A failed plugin filter leaves a clean empty output, and Plot Over Line
downstream of it survives (issue 20: ParaView crashed with SIGSEGV).

How to run (ctest does this; the line chart view needs X):

    xvfb-run -a pvpython TestFailedFilters.py <build>/lib/paraview-plugins/Translucency/Translucency.so

For each case (a filter or reader of the plugin made to fail the way a user
would: an unknown linear solver, an unknown material, a zero light
direction, an open surface, a missing Fluence, no fracture seeds, a damaged
PLY file):
1. Plot Over Line is applied downstream and shown in a line chart view while
   the pipeline is valid.
2. The failure is applied and both views are rendered: before the fix
   vtkProbeFilter crashed on the null points of the failed output.
3. The failed output is checked: the same data type, no points, no cells, no
   point, cell or field arrays, and (for point sets) a non-null vtkPoints, as
   the empty result of ParaView's Threshold.
4. The property is restored and the output is complete again.

And (issue 33 item 5) after an unknown material, the outputs of Solve
Diffusion and Outgoing Radiance downstream themselves (not a Fetch) are
empty, never the previous run's fields, until the name is repaired.

Exits non-zero on failure (unittest).
"""

import os
import shutil
import sys
import tempfile
import unittest

from paraview.simple import *  # noqa: F401,F403
from paraview import servermanager

if len(sys.argv) < 2 or not os.path.isfile(sys.argv[1]):
    sys.exit("usage: xvfb-run -a pvpython TestFailedFilters.py <Translucency plugin>")
PLUGIN = sys.argv.pop(1)
LoadPlugin(PLUGIN, ns=globals())

SOURCE_DIR = os.environ.get(
    "TRANSLUCENCY_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))


def empty_output_problems(data):
    """The checks of a clean empty output; returns a list of what is wrong."""
    problems = []
    if data.IsA("vtkCompositeDataSet"):
        it = data.NewIterator()
        it.InitTraversal()
        if not it.IsDoneWithTraversal():
            problems.append("composite output still has leaves")
        return problems
    if data.IsA("vtkDataSet"):
        if data.GetNumberOfPoints() != 0:
            problems.append("%d points" % data.GetNumberOfPoints())
        if data.GetNumberOfCells() != 0:
            problems.append("%d cells" % data.GetNumberOfCells())
        for kind, attributes in (("point", data.GetPointData()), ("cell", data.GetCellData())):
            if attributes.GetNumberOfArrays() != 0:
                problems.append("stale %s arrays %s" % (kind, [
                    attributes.GetArrayName(i) for i in range(attributes.GetNumberOfArrays())]))
    if data.IsA("vtkPointSet") and data.GetPoints() is None:
        problems.append("null vtkPoints")
    field = data.GetFieldData()
    if field is not None and field.GetNumberOfArrays() != 0:
        problems.append("stale field arrays")
    return problems


class FailedFiltersTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="translucency_failed_")
        cls.sphere = Sphere(Radius=4.0, ThetaResolution=12, PhiResolution=12)
        cls.plane = Plane()  # an open surface: Tetrahedralize Surface fails on it
        cls.triangles = Triangulate(Input=cls.sphere)
        cls.tetra = TetrahedralizeSurface(Input=cls.triangles, TargetNumberOfTets=1500)
        cls.assign = AssignScatteringCoefficients(Input=cls.tetra)
        cls.irradiance = SurfaceIrradiance(Input=cls.assign)
        cls.solve = SolveDiffusion(Input=cls.irradiance)
        cls.radiance = OutgoingRadiance(Input=cls.solve)
        cls.fracture = FractureTetMesh(Input=cls.tetra, RandomSeeds=[3, 1])
        cls.render_view = CreateView("RenderView")
        cls.chart_view = CreateView("XYChartView")

    @classmethod
    def tearDownClass(cls):
        # Views closed while the X connection is alive (else GLXBadContext at exit).
        Delete(cls.chart_view)
        Delete(cls.render_view)
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def check_failure(self, target, expected_array, fail, restore, class_name):
        """Plot Over Line on `target`; `fail()` breaks it, `restore()` repairs it."""
        line = PlotOverLine(Input=target)
        Show(target, self.render_view)
        Show(line, self.chart_view)
        Render(self.render_view)
        Render(self.chart_view)
        good = servermanager.Fetch(target)
        self.assertEqual(good.GetClassName(), class_name)
        self.assertTrue(empty_output_problems(good), "the valid output should not be empty")
        if expected_array:
            self.assertIsNotNone(good.GetPointData().GetArray(expected_array))

        fail()
        Render(self.render_view)  # crashed in vtkProbeFilter before the fix
        Render(self.chart_view)
        line.UpdatePipeline()
        failed = servermanager.Fetch(target)
        self.assertEqual(failed.GetClassName(), class_name)
        self.assertEqual(empty_output_problems(failed), [])
        probed = servermanager.Fetch(line)
        self.assertIsNotNone(probed)

        restore()
        Render(self.render_view)
        Render(self.chart_view)
        again = servermanager.Fetch(target)
        self.assertTrue(empty_output_problems(again), "the restored output should not be empty")
        if expected_array:
            self.assertIsNotNone(again.GetPointData().GetArray(expected_array))
        Hide(target, self.render_view)
        Delete(line)

    def test_unknown_linear_solver(self):
        """The case of issue 20: Solve Diffusion's Linear Solver set to an unknown name."""
        def fail():
            self.solve.LinearSolver = "nosuchsolver"

        def restore():
            self.solve.LinearSolver = ""
        self.check_failure(self.solve, "Fluence", fail, restore, "vtkUnstructuredGrid")

    def test_unknown_material(self):
        def fail():
            self.assign.MaterialName = "nosuchmaterial"

        def restore():
            self.assign.MaterialName = "marble"
        self.check_failure(self.assign, None, fail, restore, "vtkUnstructuredGrid")
        # Downstream of the failure: the solver also leaves an empty output.
        self.check_failure(self.solve, "Fluence", fail, restore, "vtkUnstructuredGrid")

    def test_no_stale_output_downstream_of_a_failure(self):
        """Issue 33 item 5 in ParaView: the filters' own outputs (not a Fetch,
        which builds a new data object) downstream of a failed filter are
        empty, never the previous run's Fluence and Radiance."""
        self.radiance.UpdatePipeline()
        own = [proxy.GetClientSideObject() for proxy in (self.solve, self.radiance)]
        self.assertIsNotNone(own[0].GetOutputDataObject(0).GetPointData().GetArray("Fluence"))
        self.assertIsNotNone(own[1].GetOutputDataObject(0).GetPointData().GetArray("Radiance"))
        self.assign.MaterialName = "nosuchmaterial"
        try:
            self.radiance.UpdatePipeline()
            for algorithm in own:
                self.assertEqual(empty_output_problems(algorithm.GetOutputDataObject(0)), [],
                                 "%s kept the previous run's output" % algorithm.GetClassName())
            # Again with nothing changed: still empty, never the old data.
            self.radiance.UpdatePipeline()
            for algorithm in own:
                self.assertEqual(empty_output_problems(algorithm.GetOutputDataObject(0)), [])
        finally:
            self.assign.MaterialName = "marble"
        self.radiance.UpdatePipeline()
        self.assertIsNotNone(own[0].GetOutputDataObject(0).GetPointData().GetArray("Fluence"))
        self.assertIsNotNone(own[1].GetOutputDataObject(0).GetPointData().GetArray("Radiance"))

    def test_bad_light(self):
        def fail():
            self.irradiance.DirectionalLights = [0, 0, 0, 1]

        def restore():
            self.irradiance.DirectionalLights = [0, -1, -1, 1]
        self.check_failure(self.irradiance, "Irradiance", fail, restore, "vtkUnstructuredGrid")

    def test_open_surface(self):
        def fail():
            self.tetra.Input = self.plane

        def restore():
            self.tetra.Input = self.triangles
        self.check_failure(self.tetra, None, fail, restore, "vtkUnstructuredGrid")

    def test_missing_fluence(self):
        def fail():
            self.radiance.Input = self.irradiance

        def restore():
            self.radiance.Input = self.solve
        self.check_failure(self.radiance, "Radiance", fail, restore, "vtkPolyData")

    def test_fracture_without_seeds(self):
        def fail():
            self.fracture.RandomSeeds = [0, 0]

        def restore():
            self.fracture.RandomSeeds = [3, 1]
        self.check_failure(self.fracture, None, fail, restore, "vtkMultiBlockDataSet")

    def test_damaged_surface_file(self):
        good = os.path.join(SOURCE_DIR, "Data", "bunny.ply")
        path = os.path.join(self.tmp, "bunny.ply")
        shutil.copyfile(good, path)
        reader = TranslucencySurfaceReader(FileName=path)

        def fail():
            with open(good, "rb") as f:
                data = f.read()
            with open(path, "wb") as f:
                f.write(data[:2000])  # header and part of the vertices
            reader.FileName = ""
            reader.FileName = path

        def restore():
            shutil.copyfile(good, path)
            reader.FileName = ""
            reader.FileName = path
        self.check_failure(reader, None, fail, restore, "vtkPolyData")


if __name__ == "__main__":
    unittest.main(verbosity=2)
