#!/usr/bin/env python3
"""Each filter's declared MPI plan is the one Documentation/Parallel.md's table says.

How to run (one process, no MPI needed; ctest does this):

    PYTHONPATH=<build>/lib/python3.11/site-packages TRANSLUCENCY_SOURCE_DIR=<source> \\
        /usr/bin/python3 TestParallelPlans.py

1. The table of "What runs where" in Documentation/Parallel.md is parsed: each
   row names a filter (and settings) and its plan ("per piece", "distributed",
   "gathered (same mesh)" or "gathered (rank 0)").
2. For every row, each filter is run in one process with representative
   settings of the row; its GetParallelPlan() (the plan the filter declares for
   more than one process, set by every execution) must start with the row's
   plan and give a reason; its GetParallelPath() is "serial" (one process).
3. Every one of the 11 public filters appears in the table, every row is
   checked, and no filter has a plan the table does not list.
4. TRANSLUCENCY_PARALLEL=gathered makes every declared plan gathered; an
   unknown value is an error naming the variable and the allowed values, and
   the filter's output is empty.

Exits non-zero on failure (unittest).
"""

import os
import re
import subprocess
import sys
import unittest

SOURCE_DIR = os.environ.get("TRANSLUCENCY_SOURCE_DIR") or os.path.abspath(
    os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
PARALLEL_MD = os.path.join(SOURCE_DIR, "Documentation", "Parallel.md")

PUBLIC_FILTERS = [
    "vtkAssignScatteringCoefficients", "vtkDetectorReadings", "vtkFractureTetMesh",
    "vtkInverseDiffusion", "vtkOutgoingRadiance", "vtkPaintScatteringCoefficients",
    "vtkSolveDiffusion", "vtkStrokeCut", "vtkSurfaceIrradiance", "vtkTetrahedralizeSurface",
    "vtkTranslucentRadiosity"]
PLANS = ("per piece", "distributed", "gathered (same mesh)", "gathered (rank 0)", "replicated")


def table_rows():
    """{first cell: plan cell} of the table under "What runs where"."""
    with open(PARALLEL_MD, encoding="utf-8") as f:
        text = f.read()
    start = text.index("## What runs where")
    rows = {}
    header = None
    for line in text[start:].splitlines()[1:]:
        if line.startswith("## "):
            break
        if not line.startswith("|"):
            if header is not None and rows:
                break  # the first table only
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if header is None:
            header = [c.lower() for c in cells]
            continue
        if set(cells[0]) <= set("-: "):
            continue
        rows[cells[0]] = cells[header.index("plan")].replace("**", "")
    return rows


def tiny_mesh():
    """Five tets of the unit cube (mm) with a material."""
    from vtkmodules.vtkCommonCore import vtkDoubleArray, vtkPoints
    from vtkmodules.vtkCommonDataModel import VTK_TETRA, vtkUnstructuredGrid
    points = vtkPoints()
    for p in [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0), (0, 0, 1), (1, 0, 1), (0, 1, 1),
              (1, 1, 1)]:
        points.InsertNextPoint(*p)
    grid = vtkUnstructuredGrid()
    grid.SetPoints(points)
    for tet in [(0, 1, 2, 4), (1, 3, 2, 7), (1, 2, 4, 7), (1, 4, 5, 7), (2, 4, 7, 6)]:
        grid.InsertNextCell(VTK_TETRA, 4, tet)
    for name, n, value in [("AbsorptionCoefficient", 3, 0.01),
                           ("ReducedScatteringCoefficient", 3, 1.0), ("RefractiveIndex", 1, 1.3)]:
        array = vtkDoubleArray()
        array.SetName(name)
        array.SetNumberOfComponents(n)
        array.SetNumberOfTuples(5)
        for c in range(n):
            array.FillComponent(c, value)
        grid.GetCellData().AddArray(array)
    return grid


def unit_image():
    """A 3 x 3 x 3 image over the unit cube (0.5 mm voxels) with uniform
    coefficients: the Volume mode's second input."""
    from vtkmodules.vtkCommonCore import vtkDoubleArray
    from vtkmodules.vtkCommonDataModel import vtkImageData
    image = vtkImageData()
    image.SetDimensions(3, 3, 3)
    image.SetSpacing(0.5, 0.5, 0.5)
    for name, value in [("AbsorptionCoefficient", 0.01), ("ReducedScatteringCoefficient", 1.0)]:
        array = vtkDoubleArray()
        array.SetName(name)
        array.SetNumberOfComponents(3)
        array.SetNumberOfTuples(27)
        for c in range(3):
            array.FillComponent(c, value)
        image.GetPointData().AddArray(array)
    return image


def surface():
    from vtkmodules.vtkFiltersCore import vtkTriangleFilter
    from vtkmodules.vtkFiltersSources import vtkCubeSource
    cube = vtkCubeSource()
    triangles = vtkTriangleFilter()
    triangles.SetInputConnection(cube.GetOutputPort())
    triangles.Update()
    return triangles.GetOutput()


def configurations():
    """{row label: [(filter class name, filter with its input set)]}."""
    import translucency as t
    from vtkmodules.vtkCommonDataModel import vtkMultiBlockDataSet, vtkPlane
    mesh = tiny_mesh()

    def on_mesh(f):
        f.SetInputData(mesh)
        return f

    def assign(mode):
        f = on_mesh(t.vtkAssignScatteringCoefficients())
        getattr(f, "SetMaterialModeTo" + mode)()
        if mode == "Volume":
            f.SetVolumeData(unit_image())
        return ("vtkAssignScatteringCoefficients", f)

    def solve(**settings):
        f = on_mesh(t.vtkSolveDiffusion())
        for key, value in settings.items():
            if key == "collimated":
                extended = mesh.NewInstance()
                extended.ShallowCopy(mesh)
                from vtkmodules.vtkCommonCore import vtkIntArray
                model = vtkIntArray()
                model.SetName("TranslucencyCollimatedModel")
                model.InsertNextValue(1)
                extended.GetFieldData().AddArray(model)
                f.SetInputData(extended)
            elif key == "TimeGates":
                f.SetTimeGates(*value)
            else:
                getattr(f, "Set" + key)(value)
        return ("vtkSolveDiffusion", f)

    def cut(**settings):
        f = on_mesh(t.vtkStrokeCut())
        plane = vtkPlane()
        plane.SetNormal(1, 0, 0)
        plane.SetOrigin(0.5, 0.5, 0.5)
        f.SetCutFunction(plane)
        for key, value in settings.items():
            getattr(f, "Set" + key)(value)
        return ("vtkStrokeCut", f)

    def single(name, prepare=None):
        f = getattr(t, name)()
        if prepare:
            prepare(f)
        else:
            on_mesh(f)
        return (name, f)

    def radiosity(f):
        blocks = vtkMultiBlockDataSet()
        blocks.SetBlock(0, mesh)
        f.SetInputData(blocks)

    def fracture(f):
        on_mesh(f)
        f.AddSeedPoint(0.2, 0.2, 0.2)

    def tetra(f):
        f.SetInputData(surface())

    return {
        "Tetrahedralize Surface": [single("vtkTetrahedralizeSurface", tetra)],
        "Assign Scattering Coefficients, Uniform, Material Ids, Spherical Inclusion, Veins":
            [assign(m) for m in ("Uniform", "MaterialIds", "SphericalInclusion", "Veins")],
        "Assign Scattering Coefficients, Layers": [assign("Layers")],
        "Assign Scattering Coefficients, Volume": [assign("Volume")],
        "Paint Scattering Coefficients": [single("vtkPaintScatteringCoefficients")],
        "Surface Irradiance": [single("vtkSurfaceIrradiance")],
        "Solve Diffusion, divergence and fem, continuous wave, any collimated model":
            [solve(), solve(Solver=1), solve(collimated=True)],
        "Solve Diffusion, Monte Carlo (continuous wave or time gates)":
            [solve(Solver=4), solve(Solver=4, TimeGates=(0.0, 1e-9, 4))],
        "Solve Diffusion, other cases": [
            solve(Solver=2), solve(Solver=3), solve(Solver=4, DistributedSolve=False),
            solve(DistributedSolve=False),
            solve(ModulationFrequency=1e8), solve(TimeGates=(0.0, 1e-9, 4)),
            solve(InteractiveDetector=True)],
        "Outgoing Radiance": [single("vtkOutgoingRadiance")],
        "Stroke Cut (implicit cutter or stroke, relaxation on or off)":
            [cut(), cut(NumberOfRelaxationIterations=0)],
        "Fracture Tet Mesh": [single("vtkFractureTetMesh", fracture)],
        "Translucent Radiosity": [single("vtkTranslucentRadiosity", radiosity)],
        "Inverse Diffusion": [single("vtkInverseDiffusion")],
        "Detector Readings": [single("vtkDetectorReadings")],
    }


def declared(f):
    """Run `f` in this process, quietly (most of these inputs are not solvable)."""
    from vtkmodules.vtkCommonCore import vtkObject
    vtkObject.GlobalWarningDisplayOff()
    f.Update()
    vtkObject.GlobalWarningDisplayOn()
    return f.GetParallelPlan(), f.GetParallelPath()


class ParallelPlansTest(unittest.TestCase):

    def test_table_parses(self):
        rows = table_rows()
        self.assertGreaterEqual(len(rows), 11)
        for label, plan in rows.items():
            self.assertIn(plan, PLANS, "row %r: unknown plan %r" % (label, plan))

    def test_every_filter_declares_the_table_plan(self):
        if "TRANSLUCENCY_PARALLEL" in os.environ:
            self.skipTest("TRANSLUCENCY_PARALLEL is set")
        rows = table_rows()
        cases = configurations()
        self.assertEqual(sorted(rows), sorted(cases),
                         "the table's rows and this test's cases must be the same")
        seen = set()
        for label, plan in rows.items():
            for name, f in cases[label]:
                seen.add(name)
                declared_plan, path = declared(f)
                with self.subTest(row=label, filter=name, plan=declared_plan):
                    self.assertTrue(declared_plan.startswith(plan + ": "),
                                    "%s declares %r, the table %r" % (name, declared_plan, plan))
                    self.assertGreater(len(declared_plan), len(plan) + 10, "no reason given")
                    self.assertEqual(path, "serial")
        self.assertEqual(sorted(seen), sorted(PUBLIC_FILTERS))

    def test_override(self):
        """TRANSLUCENCY_PARALLEL=gathered and a bad value, in a child process."""
        code = ("import sys; sys.path.insert(0, %r); import TestParallelPlans as T; "
                "rows = T.configurations(); "
                "print('\\n'.join('%%s|%%s' %% (n, T.declared(f)[0]) "
                "for cases in rows.values() for n, f in cases))"
                % os.path.dirname(os.path.abspath(__file__)))
        env = dict(os.environ, TRANSLUCENCY_PARALLEL="gathered")
        out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                             text=True, timeout=300)
        self.assertEqual(out.returncode, 0, out.stderr)
        lines = [l for l in out.stdout.splitlines() if "|" in l]
        self.assertGreater(len(lines), 11)
        for line in lines:
            name, plan = line.split("|", 1)
            self.assertTrue(plan.startswith("gathered"), line)
        bad = ("import sys; sys.path.insert(0, %r); import TestParallelPlans as T; "
               "f = T.configurations()['Paint Scattering Coefficients'][0][1]; f.Update(); "
               "print('cells', f.GetOutput().GetNumberOfCells())"
               % os.path.dirname(os.path.abspath(__file__)))
        env = dict(os.environ, TRANSLUCENCY_PARALLEL="sometimes")
        out = subprocess.run([sys.executable, "-c", bad], env=env, capture_output=True,
                             text=True, timeout=300)
        self.assertIn("TRANSLUCENCY_PARALLEL='sometimes': expected 'auto'", out.stderr)
        self.assertIn("cells 0", out.stdout)


if __name__ == "__main__":
    unittest.main()
