"""Translucency: heterogeneous translucent volumes by light diffusion on tetrahedral meshes.

Every VTK class of the project is available at top level, for example
``translucency.vtkSolveDiffusion``. Importing this package also imports the VTK
modules the classes depend on.

VTK filters only log their errors (an unknown material, an unknown solver, a
mesh that is not closed) and leave an empty output, so a script goes on and
fails later with ``None``. To stop at the first error with its message::

    import translucency
    ...
    output = translucency.update(solve)       # raises translucency.PipelineError

    with translucency.raise_on_error():       # any VTK error inside the block
        solve.SetSolverByName("femm")         # raises PipelineError at the block's end

Scripts copied anywhere find the project's data and command-line tool with
``translucency.find_data("bunny.ply")`` and ``translucency.find_cli()``.
"""

import contextlib
import os
import re
import shutil

from .TranslucencyFilters import *  # noqa: F401,F403
from .TranslucencyReaders import *  # noqa: F401,F403

__all__ = [name for name in dir() if name.startswith("vtk")] + [
    "PipelineError", "raise_on_error", "update", "find_data", "find_cli"]


class PipelineError(RuntimeError):
    """A VTK error reported while a Translucency filter (or any VTK object) ran.

    ``str(error)`` is the first message, e.g. ``vtkAssignScatteringCoefficients:
    unknown material preset 'x'; known presets: ...``; ``messages`` holds all of
    them in the order they were reported (the root cause upstream first).
    """

    def __init__(self, messages):
        self.messages = list(messages)
        text = self.messages[0] if self.messages else "VTK error"
        if len(self.messages) > 1:
            text += " (and %d more error(s): see .messages)" % (len(self.messages) - 1)
        super().__init__(text)


_PIPELINE_FAILURE = re.compile(r"returned failure for request")
_OBJECT_ADDRESS = re.compile(r"^(\w+) \(0x[0-9a-fA-F]+\): ", re.MULTILINE)


def _clean(text):
    """'ERROR: In file.cxx, line 64\\nvtkX (0x1234): message\\n\\n' -> 'vtkX: message'."""
    lines = text.strip().splitlines()
    if lines and lines[0].startswith("ERROR: In "):
        lines = lines[1:]
    return _OBJECT_ADDRESS.sub(r"\1: ", "\n".join(lines).strip())


@contextlib.contextmanager
def raise_on_error():
    """Record every VTK error message reported inside the ``with`` block
    (through vtkOutputWindow: any object, any filter of a pipeline) and raise
    :class:`PipelineError` with them at the end of the block. The messages are
    still printed as usual. The executive's own "returned failure for request"
    report is kept only if no filter said why it failed.
    """
    from vtkmodules.vtkCommonCore import vtkCommand, vtkOutputWindow
    from vtkmodules.util.misc import calldata_type
    from vtkmodules.util.vtkConstants import VTK_STRING

    messages = []

    @calldata_type(VTK_STRING)
    def record(caller, event, text):
        messages.append(_clean(text or ""))

    window = vtkOutputWindow.GetInstance()
    tag = window.AddObserver(vtkCommand.ErrorEvent, record)
    try:
        yield messages
    finally:
        window.RemoveObserver(tag)
    if messages:
        reasons = [m for m in messages if not _PIPELINE_FAILURE.search(m)]
        failures = [m.splitlines()[0] for m in messages if _PIPELINE_FAILURE.search(m)]
        raise PipelineError(reasons or failures)


def update(algorithm, port=0):
    """Update ``algorithm`` (and so everything upstream of it) and return the
    data object of its output ``port`` (default 0).

    Raises :class:`PipelineError` carrying the filter's message if any filter
    of the pipeline reports an error, instead of leaving an empty output to be
    found later::

        try:
            surface = translucency.update(radiance)
        except translucency.PipelineError as error:
            sys.exit(str(error))
    """
    with raise_on_error():
        algorithm.Update(port)
    return algorithm.GetOutputDataObject(port)


# Where this package is: <build>/lib/python3.X/site-packages/translucency in a
# build tree (with _locations.py, written by CMake, naming the source tree),
# <prefix>/lib/python3.X/site-packages/translucency once installed (the data
# in <prefix>/share/translucency/Data, the tool in <prefix>/bin).
_PREFIX = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))


def _data_dirs():
    dirs = []
    if os.environ.get("TRANSLUCENCY_DATA_DIR"):
        dirs.append(os.environ["TRANSLUCENCY_DATA_DIR"])
    try:
        from . import _locations
        dirs.append(_locations.SOURCE_DATA_DIR)
    except ImportError:
        pass
    dirs.append(os.path.join(_PREFIX, "share", "translucency", "Data"))
    return dirs


def find_data(name):
    """The path of one of the project's data files (``"bunny.ply"``,
    ``"materials.json"``, ``"cornell_box.json"``), wherever the script runs
    from: ``$TRANSLUCENCY_DATA_DIR``, the source tree of this build, or the
    installed ``<prefix>/share/translucency/Data``. Raises FileNotFoundError
    naming every place it looked."""
    tried = []
    for directory in _data_dirs():
        path = os.path.join(directory, name)
        if os.path.isfile(path):
            return path
        tried.append(path)
    raise FileNotFoundError("translucency data file %r not found; looked at: %s "
                            "(set TRANSLUCENCY_DATA_DIR to the directory holding it)"
                            % (name, ", ".join(tried)))


def find_cli():
    """The ``translucency`` command-line tool of this build or installation:
    ``$TRANSLUCENCY_CLI``, ``<build or prefix>/bin/translucency``, or the
    first on PATH. Raises FileNotFoundError naming every place it looked."""
    candidates = [os.environ.get("TRANSLUCENCY_CLI"),
                  os.path.join(_PREFIX, "bin", "translucency"), shutil.which("translucency")]
    for path in candidates:
        if path and os.path.isfile(path) and os.access(path, os.X_OK):
            return path
    raise FileNotFoundError("the translucency command-line tool was not found; looked at: %s "
                            "(set TRANSLUCENCY_CLI to its path)"
                            % ", ".join(p for p in candidates if p) or "PATH")
