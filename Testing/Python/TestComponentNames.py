#!/usr/bin/env python3
"""Every RGB array of every filter output names its components R, G, B
(issue 20: ParaView showed the colour channels as X, Y, Z).

How to run (from a build tree):

    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestComponentNames.py

1. Runs the filters on a small sphere: Tetrahedralize Surface, Assign
   Scattering Coefficients, Surface Irradiance, Solve Diffusion (divergence,
   and Monte Carlo for its extra arrays), Outgoing Radiance, Paint Scattering
   Coefficients, Stroke Cut and Fracture Tet Mesh (every piece).
2. In each output, every 3-component point or cell array is an RGB quantity
   with components named R, G, B, except the geometric vectors (Normals),
   which must not be.
3. The arrays of the data contract are there (so step 2 is not vacuous).

Exits non-zero on failure (unittest).
"""

import os
import sys
import unittest

import translucency
from vtkmodules.vtkCommonDataModel import vtkPlane

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from vtk_chain import sphere_chain  # noqa: E402

VECTORS = {"Normals"}


def leaves(data):
    if data.IsA("vtkMultiBlockDataSet"):
        for k in range(data.GetNumberOfBlocks()):
            yield from leaves(data.GetBlock(k))
    elif data is not None:
        yield data


def triple_arrays(data):
    """(where, name, component names) of every 3-component array of `data`."""
    for where, attributes in (("point", data.GetPointData()), ("cell", data.GetCellData())):
        for i in range(attributes.GetNumberOfArrays()):
            array = attributes.GetArray(i)
            if array is not None and array.GetNumberOfComponents() == 3:
                names = tuple(array.GetComponentName(c) for c in range(3))
                yield where, array.GetName(), names


class ComponentNamesTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        chain = sphere_chain(material=None)
        tetra, assign, light, solve = chain.tetra, chain.material, chain.light, chain.solve
        monte_carlo = translucency.vtkSolveDiffusion()
        monte_carlo.SetInputConnection(light.GetOutputPort())
        monte_carlo.SetSolverByName("montecarlo")
        monte_carlo.SetNumberOfPhotons(2000)
        radiance = translucency.vtkOutgoingRadiance()
        radiance.SetInputConnection(solve.GetOutputPort())
        paint = translucency.vtkPaintScatteringCoefficients()
        paint.SetInputConnection(assign.GetOutputPort())
        paint.AddStrokePoint(0.0, 0.0, 4.0)
        paint.AddStrokePoint(0.0, 4.0, 0.0)
        paint.SetWidth(2.0)
        cut = translucency.vtkStrokeCut()
        cut.SetInputConnection(solve.GetOutputPort())
        plane = vtkPlane()
        plane.SetNormal(1.0, 0.0, 0.0)
        cut.SetCutFunction(plane)
        fracture = translucency.vtkFractureTetMesh()
        fracture.SetInputConnection(solve.GetOutputPort())
        fracture.SetRandomSeeds(2, 1)
        cls.outputs = {}
        for name, algorithm in (("tetrahedralize", tetra), ("assign", assign),
                                ("irradiance", light), ("solve", solve),
                                ("montecarlo", monte_carlo), ("radiance", radiance),
                                ("paint", paint), ("cut", cut), ("fracture", fracture)):
            cls.outputs[name] = list(leaves(translucency.update(algorithm)))

    def test_rgb_arrays_name_their_components(self):
        checked = set()
        for filter_name, datasets in self.outputs.items():
            self.assertTrue(datasets, filter_name)
            for data in datasets:
                for where, name, components in triple_arrays(data):
                    with self.subTest(filter=filter_name, array=name, association=where):
                        if name in VECTORS:
                            self.assertNotEqual(components, ("R", "G", "B"))
                        else:
                            self.assertEqual(components, ("R", "G", "B"))
                        checked.add(name)
        for name in ("AbsorptionCoefficient", "ReducedScatteringCoefficient", "Irradiance",
                     "Fluence", "Radiance", "FluenceStandardError", "MonteCarloRadiance"):
            self.assertIn(name, checked)

    def test_every_filter_output_has_an_rgb_array(self):
        for filter_name, datasets in self.outputs.items():
            if filter_name == "tetrahedralize":
                continue
            for data in datasets:
                names = [name for _, name, _ in triple_arrays(data) if name not in VECTORS]
                self.assertTrue(names, "%s: no RGB array" % filter_name)


if __name__ == "__main__":
    unittest.main(verbosity=2)
