"""The one harness of the MPI suites of Testing/Python (TestParallel,
TestDistributedSolve, TestDistributedIrradiance; TestParallelServer uses its
runner and sphere).

A suite is a pvbatch script with two modes and a unittest that compares:

1. `pvbatch <script> <plugin> <work> prepare` (one process) writes the mesh,
   its partitioned copies (.pvtu: write_pieces, mark_global_ids) and the
   serial references;
2. `mpiexec --allow-run-as-root --oversubscribe -n N pvbatch [--symmetric]
   <script> <plugin> <work> run` runs the same chains on distributed data;
   each rank writes its results (.pvtu / .pvtp) and its report lines
   ("<key> <case> rank <r> ...") to its own file <stem>_<rank>.txt;
3. the suite (a MpiSuite) reads them back: pieces_of, rank_reports,
   assert_error_on_every_rank.

Time limits (the ctest TIMEOUT convention): each step has a ceiling that
tells a hang from a slow run on a loaded machine (MpiSuite.TIME_LIMIT); a
step past it is ended with every rank and its output says HUNG. ctest's
TIMEOUT (passed as TRANSLUCENCY_TEST_TIMEOUT by translucency_add_mpi_suite
in Testing/CMakeLists.txt) must exceed prepare + run + MARGIN, so that the
harness, which names the hang, always fires before ctest, which only kills;
MpiSuite checks this before it starts.

The command line: `<suite>.py <Translucency plugin> [<number of ranks, 2>]`.
"""

import os
import re
import signal
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
# (The pipeline scripts import this module too, with other arguments.)
PLUGIN = sys.argv[1] if len(sys.argv) > 1 else ""
RANKS = int(sys.argv[2]) if len(sys.argv) > 2 and sys.argv[2].isdigit() else 2
MARGIN = 30  # seconds of ctest TIMEOUT beyond the two steps' limits
MPIEXEC = ["mpiexec", "--allow-run-as-root", "--oversubscribe"]


# ---- test side (python3) ----

def run(command, work, limit):
    """The finished process, or one with returncode None that says it hung.
    A hung mpiexec gets SIGTERM (it ends its ranks), then its process group
    SIGKILL, so that no rank is left running."""
    env = None
    if command[:len(MPIEXEC)] == MPIEXEC:
        # The ranks choose their OpenMP threads themselves (cores / ranks on
        # the node, Filters/Parallel/vtkTranslucencyThreads.h): ctest's
        # OMP_NUM_THREADS, an explicit choice the product would honour, is
        # not passed on, so that policy is what runs here.
        env = {k: v for k, v in os.environ.items() if k != "OMP_NUM_THREADS"}
    process = subprocess.Popen(command, cwd=work, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, start_new_session=True, env=env)
    try:
        out, err = process.communicate(timeout=limit)
        return subprocess.CompletedProcess(command, process.returncode, out, err)
    except subprocess.TimeoutExpired:
        process.terminate()
        try:
            out, err = process.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            out, err = "", ""
        try:
            os.killpg(process.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        if process.poll() is None:
            out, err = process.communicate()
        return subprocess.CompletedProcess(
            command, None, out, err + "\nHUNG: no end after %d s: %s" % (limit, " ".join(command)))


def check_time_limits(limits):
    """Fails when ctest's TIMEOUT (TRANSLUCENCY_TEST_TIMEOUT, if set) leaves
    less than MARGIN s beyond the steps' own limits."""
    timeout = os.environ.get("TRANSLUCENCY_TEST_TIMEOUT")
    needed = sum(limits.values()) + MARGIN
    if timeout and float(timeout) < needed:
        raise AssertionError("ctest TIMEOUT %s s is below the harness's limits %s + %d s: "
                             "raise it to %d (Testing/Python/mpi_harness.py)"
                             % (timeout, limits, MARGIN, needed))


class MpiSuite(unittest.TestCase):
    """setUpClass runs SCRIPT's prepare step (its stdout must contain
    PREPARED), then its run step on RANKS ranks (--symmetric if SYMMETRIC);
    cls.work is the working folder, cls.prepare and cls.result the two
    finished processes (result.returncode None: it hung). Subclasses set the
    class attributes and may override parse() to read the rank files."""

    SCRIPT = None
    PREPARED = "prepared"
    SYMMETRIC = True
    TIME_LIMIT = {"prepare": 150, "run": 200}  # seconds: hang ceilings for a loaded machine

    @classmethod
    def setUpClass(cls):
        check_time_limits(cls.TIME_LIMIT)
        cls.tmp = tempfile.TemporaryDirectory()
        cls.work = cls.tmp.name
        script = os.path.join(HERE, cls.SCRIPT)
        cls.prepare = run(["pvbatch", script, PLUGIN, cls.work, "prepare"], cls.work,
                          cls.TIME_LIMIT["prepare"])
        if cls.prepare.returncode != 0 or cls.PREPARED not in cls.prepare.stdout:
            cls.tmp.cleanup()
            raise AssertionError("prepare failed:\n" + cls.prepare.stdout + cls.prepare.stderr)
        cls.result = run(MPIEXEC + ["-n", str(RANKS), "pvbatch"] +
                         (["--symmetric"] if cls.SYMMETRIC else []) +
                         [script, PLUGIN, cls.work, "run"], cls.work, cls.TIME_LIMIT["run"])
        try:
            cls.parse()
        except Exception:
            cls.tmp.cleanup()
            raise

    @classmethod
    def parse(cls):
        pass

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    @classmethod
    def rank_text(cls, stem, rank):
        """The text of <work>/<stem>_<rank>.txt, "" if that rank wrote none."""
        name = os.path.join(cls.work, "%s_%d.txt" % (stem, rank))
        if not os.path.exists(name):
            return ""
        with open(name) as f:
            return f.read()

    @classmethod
    def rank_reports(cls, stem, pattern):
        """{case: {rank: match}} over every rank's <stem>_<rank>.txt, for the
        lines that match `pattern` (a regular expression whose groups 1 and
        2 are the case and the rank)."""
        found = {}
        for rank in range(RANKS):
            for m in re.finditer(pattern, cls.rank_text(stem, rank), re.M):
                found.setdefault(m.group(1), {})[int(m.group(2))] = m
        return found

    def assert_error_on_every_rank(self, message, once=False, failures=None):
        """The run's one expected error `message` is reported by every rank
        (exactly once each if `once`) and no other error is logged; with
        `failures`, the executive's "returned failure" appears that many times."""
        stderr = self.result.stderr
        lines = [line for line in stderr.splitlines() if "ERR|" in line]
        for rank in range(RANKS):
            if once:
                self.assertEqual(sum(1 for line in lines
                                     if "pvbatch.%d " % rank in line and message in line), 1,
                                 "rank %d reports the error once" % rank)
            else:
                self.assertTrue(any("pvbatch.%d " % rank in line and message in line
                                    for line in lines), "rank %d reports the error" % rank)
        unexpected = [line for line in lines
                      if message not in line and "returned failure for request" not in line]
        self.assertEqual(unexpected, [])
        if failures is not None:
            self.assertEqual(len(re.findall("returned failure", stderr)), failures)


def pieces_of(name):
    """The pieces of a .pvtu or .pvtp file, each a copy."""
    from vtkmodules.vtkIOXML import vtkXMLPPolyDataReader, vtkXMLPUnstructuredGridReader
    reader = vtkXMLPPolyDataReader() if name.endswith(".pvtp") else vtkXMLPUnstructuredGridReader()
    reader.SetFileName(name)
    reader.Update()
    pieces = []
    for k in range(reader.GetNumberOfPieces()):
        reader.UpdatePiece(k, reader.GetNumberOfPieces(), 0)
        piece = reader.GetOutput().NewInstance()
        piece.DeepCopy(reader.GetOutput())
        pieces.append(piece)
    return pieces


def worst_relative(value, reference, scale, floor=1e-12):
    """max |value - reference| / max(|reference|, floor scale)."""
    import numpy as np
    return float(np.max(np.abs(value - reference) /
                        np.maximum(np.abs(reference), floor * scale)))


def main():
    unittest.main(argv=sys.argv[:1], verbosity=2)


# ---- pvbatch side (the prepare steps; plain VTK, one process) ----

def read_mesh(name):
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(name)
    reader.Update()
    return reader.GetOutput()


def write_mesh(mesh, name):
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridWriter
    writer = vtkXMLUnstructuredGridWriter()
    writer.SetInputData(mesh)
    writer.SetFileName(name)
    writer.Write()


def use_float_points(mesh):
    """Float points in place (vtkExtractUnstructuredGridPiece writes float
    points: the whole mesh then has the very same coordinates as its pieces)."""
    from vtkmodules.vtkCommonCore import vtkPoints
    points = vtkPoints()
    points.SetDataTypeToFloat()
    points.DeepCopy(mesh.GetPoints())
    mesh.SetPoints(points)


def add_ids(data, name, count, first, step):
    """A vtkIdTypeArray `name` of first + step i, i < count, added to `data`
    (point or cell data): an identity that survives partitioning."""
    from vtkmodules.vtkCommonCore import vtkIdTypeArray
    ids = vtkIdTypeArray()
    ids.SetName(name)
    ids.SetNumberOfTuples(count)
    for i in range(count):
        ids.SetValue(i, first + step * i)
    data.AddArray(ids)


def write_pieces(mesh, name, pieces, ghosts):
    """`mesh` split by vtkExtractUnstructuredGridPiece into <name>.pvtu and
    <name>_<k>.vtu, `pieces` pieces with `ghosts` levels of ghost cells."""
    from vtkmodules.vtkFiltersParallel import vtkExtractUnstructuredGridPiece
    from vtkmodules.vtkIOParallelXML import vtkXMLPUnstructuredGridWriter
    split = vtkExtractUnstructuredGridPiece()
    split.SetInputData(mesh)
    writer = vtkXMLPUnstructuredGridWriter()
    writer.SetInputConnection(split.GetOutputPort())
    writer.SetFileName(name + ".pvtu")
    writer.SetNumberOfPieces(pieces)
    writer.SetStartPiece(0)
    writer.SetEndPiece(pieces - 1)
    writer.SetGhostLevel(ghosts)
    writer.Write()


def mark_global_ids(name, pieces, point="PointIds", cell=None):
    """Marks the plain id arrays of <name>.pvtu and its pieces as GlobalIds
    (vtkExtractUnstructuredGridPiece drops the attribute): `point` in the
    point data, `cell` (if given) in the cell data."""
    with open(name + ".pvtu") as f:
        text = f.read()
    text = text.replace("<PPointData>", '<PPointData GlobalIds="%s">' % point)
    if cell:
        text = text.replace("<PCellData>", '<PCellData GlobalIds="%s">' % cell)
    with open(name + ".pvtu", "w") as f:
        f.write(text)
    for k in range(pieces):
        piece = read_mesh("%s_%d.vtu" % (name, k))
        piece.GetPointData().SetActiveGlobalIds(point)
        if cell:
            piece.GetCellData().SetActiveGlobalIds(cell)
        write_mesh(piece, "%s_%d.vtu" % (name, k))
