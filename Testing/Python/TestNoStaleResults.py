#!/usr/bin/env python3
"""No stale results in a plain VTK pipeline (issue 33 item 5): after an
upstream filter fails, a plain `Update()` of a filter downstream leaves its
output empty, never the previous run's fields.

Why it needs the filters' help: when a filter upstream fails, VTK's executive
does not call RequestData of the filters below it, so without more their
outputs keep what the last good run computed (a typo in the material name
left the last good material's Fluence on Solve Diffusion's output). Every
filter of the project empties its outputs in RequestUpdateExtent, which the
pipeline calls only on a filter about to execute, before anything upstream.

How to run (from a build tree):

    PYTHONPATH=<build>/lib/python3.11/site-packages /usr/bin/python3 TestNoStaleResults.py

1. A valid chain sphere -> tets -> material -> light -> solve -> radiance is
   updated with the plain VTK Update(): Fluence and Radiance are there.
2. The material name gets a typo; Update() of Outgoing Radiance (the end of
   the chain) is called, as a user would, without translucency.update().
   Every output from the material down is a clean empty data set (no points,
   no cells, no arrays); the material's error is reported.
3. Update() again with nothing changed: still empty (the downstream filters
   now run on the empty input and report their own error), never the old data.
4. The name repaired: Fluence again, equal to the first run's (same inputs:
   the failure left no trace in the warm start either).
5. A filter that fails itself (an unknown linear solver): its own and the
   downstream outputs are empty, and the reference run comes back after repair.
6. Nothing changed and nothing failed: an Update() does not empty a valid
   output (RequestUpdateExtent is not called on an up-to-date filter).

Exits non-zero on failure (unittest).
"""

import os
import sys
import unittest

import numpy as np
import translucency
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkCommand, vtkOutputWindow

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from vtk_chain import sphere_chain  # noqa: E402


class ErrorRecorder:
    """Collects the text of every VTK error while installed."""

    def __init__(self):
        self.messages = []
        self.window = vtkOutputWindow.GetInstance()
        self.tag = None

    def __enter__(self):
        from vtkmodules.util.misc import calldata_type
        from vtkmodules.util.vtkConstants import VTK_STRING

        @calldata_type(VTK_STRING)
        def record(caller, event, text):
            self.messages.append(text or "")
        self._record = record
        self.tag = self.window.AddObserver(vtkCommand.ErrorEvent, record)
        return self

    def __exit__(self, *exc):
        self.window.RemoveObserver(self.tag)
        return False


def problems_of_empty(data):
    """What makes `data` not a clean empty data set (a list; empty if clean)."""
    problems = []
    if data.GetNumberOfPoints() != 0:
        problems.append("%d points" % data.GetNumberOfPoints())
    if data.GetNumberOfCells() != 0:
        problems.append("%d cells" % data.GetNumberOfCells())
    for kind, attributes in (("point", data.GetPointData()), ("cell", data.GetCellData()),
                             ("field", data.GetFieldData())):
        if attributes.GetNumberOfArrays() != 0:
            problems.append("stale %s arrays %s" % (kind, [
                attributes.GetArrayName(i) for i in range(attributes.GetNumberOfArrays())]))
    return problems


class NoStaleResultsTest(unittest.TestCase):

    def setUp(self):
        chain = sphere_chain()
        self.sphere, self.tetra, self.material = chain.sphere, chain.tetra, chain.material
        self.light, self.solve = chain.light, chain.solve
        self.solve.SetRelTol(1e-10)
        self.radiance = translucency.vtkOutgoingRadiance()
        self.radiance.SetInputConnection(self.solve.GetOutputPort())
        self.downstream = [self.material, self.light, self.solve, self.radiance]

    def fluence(self):
        array = self.solve.GetOutput().GetPointData().GetArray("Fluence")
        self.assertIsNotNone(array, "no Fluence on Solve Diffusion's output")
        return vtk_to_numpy(array).copy()

    def good_run(self):
        self.radiance.Update()
        fluence = self.fluence()
        self.assertGreater(fluence.max(), 0.0)
        self.assertIsNotNone(self.radiance.GetOutput().GetPointData().GetArray("Radiance"))
        return fluence

    def assert_all_empty(self, filters, when):
        for algorithm in filters:
            problems = problems_of_empty(algorithm.GetOutputDataObject(0))
            self.assertEqual(problems, [], "%s: %s's output is stale" % (
                when, algorithm.GetClassName()))

    def test_upstream_typo_leaves_every_downstream_output_empty(self):
        reference = self.good_run()
        with ErrorRecorder() as errors:
            self.material.SetMaterialName("marbel")
            self.radiance.Update()  # plain VTK, no translucency.update()
        self.assertTrue(any("marbel" in m for m in errors.messages), errors.messages)
        self.assert_all_empty(self.downstream, "after the typo")
        # Again, nothing changed: the downstream filters now run on the empty
        # input and say so; their outputs stay empty.
        with ErrorRecorder() as errors:
            self.radiance.Update()
        self.assertTrue(errors.messages, "a filter downstream of an empty input said nothing")
        self.assert_all_empty(self.downstream, "after a second Update()")
        self.material.SetMaterialName("marble")
        repaired = self.good_run()
        np.testing.assert_allclose(repaired, reference, rtol=1e-6, atol=0.0)

    def test_own_failure_leaves_own_and_downstream_outputs_empty(self):
        reference = self.good_run()
        with ErrorRecorder() as errors:
            self.solve.SetLinearSolver("nosuchsolver")
            self.radiance.Update()
        self.assertTrue(any("nosuchsolver" in m for m in errors.messages), errors.messages)
        self.assert_all_empty([self.solve, self.radiance], "after the unknown linear solver")
        # The filters above the failure were not re-run and keep their results.
        self.assertIsNotNone(
            self.light.GetOutput().GetPointData().GetArray("Irradiance"))
        self.solve.SetLinearSolver("")
        repaired = self.good_run()
        np.testing.assert_allclose(repaired, reference, rtol=1e-6, atol=0.0)

    def test_up_to_date_update_keeps_the_output(self):
        reference = self.good_run()
        mtime = self.solve.GetOutput().GetMTime()
        self.radiance.Update()
        self.solve.Update()
        self.assertEqual(self.solve.GetOutput().GetMTime(), mtime)
        np.testing.assert_array_equal(self.fluence(), reference)
        self.assertGreater(self.radiance.GetOutput().GetNumberOfPoints(), 0)


if __name__ == "__main__":
    unittest.main(verbosity=2)
