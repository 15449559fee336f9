#!/usr/bin/env python3
"""The ParaView GUI with the Translucency plugin, as a user meets it (issue 20).

How to run (ctest does this; needs an X display, e.g. Xvfb):

    xvfb-run -a -s "-screen 0 1280x1024x24" /usr/bin/python3 TestParaViewGui.py \\
        <Translucency plugin .so> [--update-baseline]

1. Starts `paraview --dr --script=ParaViewGuiChain.py` (the GUI itself, not
   pvpython): the script builds the chain on the bunny, makes Solve Diffusion
   the active source (its Properties panel), paints a stroke with Paint
   Scattering Coefficients (its polyline widget), puts Plot Over Line downstream in
   a line chart view, applies an unknown Linear Solver (the SIGSEGV of issue
   20), repairs it, saves the render view and quits the application.
2. Checks that the GUI survived: exit code 0 (a crash gives a signal), the
   marker written at the end of the script, no error.txt.
3. Checks what the script saw: the Linear Solver drop-down lists this build's
   solvers, "default" first, and follows the Solver chosen in the panel (only
   what it accepts; an unaccepted choice goes back to "default"); the failed Solve Diffusion output was a clean
   empty vtkUnstructuredGrid (vtkPoints present, no arrays) and Outgoing
   Radiance downstream empty; after the repair, Radiance again.
4. Paint Scattering Coefficients (issue 33): created without a VTK warning
   or error (the GUI's pop-up "minimum of 1 points required" of a stroke
   widget without handles), its first stroke from the input's bounds (two
   handles across the front, mid-height); its stroke widget visible: the
   view with Paint's panel differs from the view without it in more than 200
   pixels. The whole screen (xwd, cropped, as PNG) and the view are kept in
   Testing/Temporary; with --update-baseline they are also written to
   Documentation/images/gui_paint.png and gui_paint_widget.png (128 colours).
4a. Solve Diffusion's tables (issue 33): Point Sources, Pencil Beams,
   Detectors and Time Snapshots are visible with the advanced properties
   on, each with its label and the column headers of the XML's
   ShowComponentLabels, as read from the Qt widgets
   (Plugin/TranslucencyPanelInspector.cxx); the picture of that part of the
   panel is kept and, with --update-baseline, written to
   Documentation/images/gui_solve_tables.png.
5. Compares the render view (640 x 480, Outgoing Radiance magnitude on a fixed
   0..1/1.3^2 W/(mm^2 sr) Inferno scale, fixed camera) with the baseline
   Testing/Baselines/paraview_gui_bunny.png (vtkImageDifference, the
   tolerances of TestDemoImage). The baseline was made by this test with
   --update-baseline and looked at: the marble bunny lit from above-front,
   brighter on the top of the back and the ears, darker underneath (remade
   in session 27 for the 3,000-tet hxt mesh: a coarser silhouette).

Exits non-zero on failure (unittest).
"""

import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkImagingCore import vtkImageDifference
from vtkmodules.vtkIOImage import vtkPNGReader

UPDATE = "--update-baseline" in sys.argv
ARGS = [a for a in sys.argv[1:] if a != "--update-baseline"]
if not ARGS or not os.path.isfile(ARGS[0]):
    sys.exit("usage: xvfb-run -a python3 TestParaViewGui.py <Translucency plugin> "
             "[--update-baseline]")
PLUGIN = os.path.abspath(ARGS[0])
del sys.argv[1:]

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE_DIR = os.environ.get("TRANSLUCENCY_SOURCE_DIR") or os.path.abspath(
    os.path.join(HERE, "..", ".."))
SCRIPT = os.path.join(HERE, "ParaViewGuiChain.py")
BASELINE = os.path.join(SOURCE_DIR, "Testing", "Baselines", "paraview_gui_bunny.png")
PARAVIEW = shutil.which("paraview") or "/usr/bin/paraview"
# The GUI's own time limit, below the ctest TIMEOUT so that a hung GUI is
# reported here (with its log) rather than killed by ctest.
GUI_TIMEOUT = 540

# Image comparison as in TestDemoImage.py (vtkImageDifference, AllowShift and
# Averaging on): per pixel and channel differences up to 16 of 255 levels are
# ignored (silhouette rasterisation, GL driver); the thresholded error may be
# the equivalent of 10 fully wrong pixels; the mean absolute difference over
# all pixels and channels at most 2 levels.
PIXEL_THRESHOLD = 16
IMAGE_TOLERANCE = 10.0
MEAN_TOLERANCE = 2.0
MIN_FOREGROUND = 0.10


def read_png(path):
    reader = vtkPNGReader()
    reader.SetFileName(path)
    reader.Update()
    image = reader.GetOutput()
    if image.GetNumberOfPoints() == 0:
        raise AssertionError("cannot read the image %s" % path)
    return image


def pixels(image):
    return vtk_to_numpy(image.GetPointData().GetScalars()).astype(int)


def foreground_fraction(image):
    """Fraction of pixels that differ from the corner (background) colour."""
    rgb = pixels(image)[:, :3]
    return float(np.mean(np.abs(rgb - rgb[0]).sum(axis=1) > 30))


def xwd_to_png(xwd, png):
    """An X window dump (xwd -root: ZPixmap, 24 or 32 bits per pixel, true
    colour) written as a PNG with VTK; returns `png`."""
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkIOImage import vtkPNGWriter
    with open(xwd, "rb") as f:
        data = f.read()
    header = np.frombuffer(data[:100], dtype=">u4")
    (header_size, _version, pixmap_format, _depth, width, height, _xoffset, byte_order,
     _unit, _bit_order, _pad, bits_per_pixel, bytes_per_line, _visual, red_mask, green_mask,
     blue_mask, _bits_per_rgb, _entries, ncolors) = (int(v) for v in header[:20])
    if pixmap_format != 2 or bits_per_pixel not in (24, 32):
        raise AssertionError("%s: not a true-colour ZPixmap dump" % xwd)
    start = header_size + 12 * ncolors
    rows = np.frombuffer(data[start:start + bytes_per_line * height], dtype=np.uint8)
    rows = rows.reshape(height, bytes_per_line)[:, :width * bits_per_pixel // 8]
    raw = rows.reshape(height, width, bits_per_pixel // 8).astype(np.uint32)
    if byte_order == 1:  # MSBFirst
        raw = raw[:, :, ::-1]
    value = sum(raw[:, :, k] << (8 * k) for k in range(raw.shape[2]))

    def channel(mask):
        shift = (mask & -mask).bit_length() - 1
        return ((value & mask) >> shift).astype(np.uint8)
    rgb = np.dstack([channel(red_mask), channel(green_mask), channel(blue_mask)])
    # Cropped to the windows (the screen's black background around them left out).
    rows_used = np.flatnonzero(rgb.any(axis=(1, 2)))
    columns_used = np.flatnonzero(rgb.any(axis=(0, 2)))
    if rows_used.size and columns_used.size:
        rgb = rgb[rows_used[0]:rows_used[-1] + 1, columns_used[0]:columns_used[-1] + 1]
    height, width = rgb.shape[:2]
    image = vtkImageData()
    image.SetDimensions(width, height, 1)
    flat = np.ascontiguousarray(rgb[::-1].reshape(-1, 3))  # VTK's rows go up
    image.GetPointData().SetScalars(numpy_to_vtk(flat, deep=1))
    writer = vtkPNGWriter()
    writer.SetFileName(png)
    writer.SetInputData(image)
    writer.Write()
    return png


def keep_for_inspection(png, name="TestParaViewGui.png"):
    binary_dir = os.environ.get("TRANSLUCENCY_BINARY_DIR")
    if not binary_dir:
        return png
    kept = os.path.join(binary_dir, "Testing", "Temporary", name)
    os.makedirs(os.path.dirname(kept), exist_ok=True)
    shutil.copyfile(png, kept)
    return kept


class ParaViewGuiTest(unittest.TestCase):
    maxDiff = None  # the GUI script's whole traceback

    @classmethod
    def setUpClass(cls):
        cls._tmp = tempfile.TemporaryDirectory(prefix="translucency-gui-")
        cls.out = cls._tmp.name
        env = dict(os.environ, TRANSLUCENCY_PLUGIN=PLUGIN, TRANSLUCENCY_SOURCE_DIR=SOURCE_DIR,
                   TRANSLUCENCY_GUI_OUT=cls.out)
        try:
            cls.result = subprocess.run(
                [PARAVIEW, "--dr", "--script=" + SCRIPT], env=env, cwd=cls.out,
                capture_output=True, text=True, timeout=GUI_TIMEOUT)
        except subprocess.TimeoutExpired as expired:
            cls.result = None
            cls.timeout_log = (expired.stderr or b"")[-4000:]

    @classmethod
    def tearDownClass(cls):
        cls._tmp.cleanup()

    def file(self, name):
        return os.path.join(self.out, name)

    def setUp(self):
        if self.result is None:
            self.fail("the GUI did not quit within %d s: %s" % (GUI_TIMEOUT, self.timeout_log))

    def test_gui_survived_and_quit(self):
        error = ""
        if os.path.exists(self.file("error.txt")):
            with open(self.file("error.txt")) as f:
                error = f.read()
        self.assertEqual(error, "", "the GUI script raised")
        self.assertEqual(self.result.returncode, 0,
                         "paraview exited with %d (negative: killed by a signal); its log:\n%s"
                         % (self.result.returncode, self.result.stderr[-4000:]))
        self.assertTrue(os.path.exists(self.file("marker")),
                        "the GUI did not reach the end of the script")
        # Where the GUI's time went (seconds since the script started, per stage).
        print("stages (s): %s" % self.results()["seconds"], file=sys.stderr)

    def results(self):
        path = self.file("results.json")
        self.assertTrue(os.path.exists(path), "no results.json: " + self.result.stderr[-4000:])
        with open(path) as f:
            return json.load(f)

    def test_linear_solver_drop_down(self):
        # The panel of the divergence solver (the applied Solver): its names.
        choices = self.results()["linear_solver_choices"]
        self.assertEqual(choices[0], "default")
        for name in ("cg-jacobi", "multigrid-agg"):
            self.assertIn(name, choices)
        self.assertEqual(
            choices, self.results()["linear_solver_choices_by_solver"]["divergence"])

    def test_linear_solver_drop_down_follows_the_solver(self):
        # Issue 33: the Linear Solver list offered solvers the chosen Solver
        # cannot use. The panel's decorator sets the drop-down to "default"
        # and the chosen Solver's row of LinearSolverTable (the registry's
        # lists, TestSolveDiffusionRegistry) as the Solver changes, before Apply.
        choices = self.results()["linear_solver_choices_by_solver"]
        table = {}
        for solver, name in choices["table"]:
            table.setdefault(solver, []).append(name)
        for solver in ("divergence", "fem", "quadgraph", "grid", "montecarlo", "sp3"):
            with self.subTest(solver=solver):
                self.assertEqual(choices[solver], ["default"] + table.get(solver, []))
        self.assertEqual(choices["sp3"], ["default", "bicgstab", "multigrid-agg"])
        self.assertEqual(choices["grid"], ["default", "bicgstab", "relaxation"])
        self.assertEqual(choices["montecarlo"], ["default"])
        self.assertIn("multigrid-agg", choices["divergence"])
        self.assertNotIn("relaxation", choices["divergence"])
        # quadgraph's "relaxation", then divergence: back to "default".
        self.assertEqual(choices["value_after_switch"], "default")

    def test_colouring_by_a_named_component_with_units(self):
        # Issue 33: ParaView coloured Fluence by the magnitude of (R, G, B), an
        # unphysical quantity, with no unit. The plugin's settings make it the
        # component G with the unit in the colour bar's title.
        colouring = self.results()["default_colouring"]
        for name, title in (("radiance", "Radiance (W/(mm^2 sr))"),
                            ("fluence", "Fluence (W/mm^2)")):
            with self.subTest(array=name):
                found = colouring[name]
                self.assertEqual(found["array"][1], name.capitalize())
                self.assertEqual(found["vector_mode"], "Component")
                self.assertEqual(found["vector_component"], 1)
                self.assertEqual(found["title"], title)
                self.assertEqual(found["component_title"], "G")
        png = self.file("fluence_colour_bar.png")
        self.assertGreater(foreground_fraction(read_png(png)), MIN_FOREGROUND)
        keep_for_inspection(png, "TestParaViewGui_fluence_colour_bar.png")
        if UPDATE:
            shutil.copyfile(png, os.path.join(SOURCE_DIR, "Documentation", "images",
                                              "gui_fluence_colour_bar.png"))

    def test_default_light_and_interactive_light(self):
        results = self.results()
        # The panel's defaults are the project's one default lighting (the
        # CLI's directional:0,-1,-1:1 uniform:0.1), and give exactly the
        # Irradiance of the same lights set explicitly.
        self.assertEqual(results["default_directional_lights"], [0.0, -1.0, -1.0, 1.0])
        self.assertAlmostEqual(results["default_uniform"], 0.1)
        self.assertGreater(results["default_points"], 500)
        self.assertEqual(results["default_vs_explicit_max_diff"], 0.0)
        self.assertEqual(results["default_description"], "directional:0,-1,-1:1 uniform:0.1")
        # The line widget starts above and behind the object, at its centre.
        xmin, xmax, ymin, ymax, zmin, zmax = results["bounds"]
        p1, p2 = results["interactive_point1"], results["interactive_point2"]
        for got, want in zip(p1, ((xmin + xmax) / 2, ymax, zmax)):
            self.assertAlmostEqual(got, want, places=3)
        for got, want in zip(p2, ((xmin + xmax) / 2, (ymin + ymax) / 2, (zmin + zmax) / 2)):
            self.assertAlmostEqual(got, want, places=3)
        self.assertGreater(results["interactive_adds_light"], 0.0)
        self.assertTrue(results["interactive_description"].startswith(
            "directional:0,-1,-1:1 directional:"), results["interactive_description"])

    def test_paint_stroke_drawn_as_a_polyline(self):
        # Two handles 16 mm apart, Width 1.5 mm: painted along the line (as
        # two points alone, a few tets around each end would be).
        self.assertGreater(self.results()["paint_cells_above_half"], 20)

    def test_paint_created_without_a_pop_up_and_a_stroke_to_show(self):
        # Issue 33: creating Paint popped up "minimum of 1 points required"
        # (its polyline widget without handles) and showed no stroke.
        results = self.results()
        self.assertEqual(results["paint_creation_messages"], [],
                         "VTK warnings or errors (the GUI's pop-up) on creating Paint")
        stroke = results["paint_default_stroke"]
        self.assertEqual(len(stroke), 6, "the first stroke has two handles")
        xmin, xmax, ymin, ymax, zmin, zmax = results["bounds"]
        expected = [xmin, (ymin + ymax) / 2, zmax, xmax, (ymin + ymax) / 2, zmax]
        for got, want in zip(stroke, expected):
            self.assertAlmostEqual(got, want, places=3)

    def test_paint_stroke_widget_is_visible(self):
        # The render view with Paint's panel (its widget shown) and with
        # another source's panel (no widget), same camera and data: the
        # stroke (line and handles) must change enough pixels to be seen.
        shown = pixels(read_png(self.file("paint_widget_shown.png")))[:, :3]
        hidden = pixels(read_png(self.file("paint_widget_hidden.png")))[:, :3]
        self.assertEqual(shown.shape, hidden.shape)
        changed = int(np.sum(np.abs(shown - hidden).sum(axis=1) > 60))
        print("the stroke widget changes %d pixels of the view" % changed)
        self.assertGreater(changed, 200, "the stroke widget is not visible in the view")
        png = xwd_to_png(self.file("paint_gui.xwd"), self.file("paint_gui.png"))
        keep_for_inspection(png, "TestParaViewGui_paint.png")
        keep_for_inspection(self.file("paint_widget_shown.png"),
                            "TestParaViewGui_paint_widget.png")
        if UPDATE:
            from PIL import Image  # python3-pil: 128 colours keep the PNGs small
            for source, name in ((png, "gui_paint.png"),
                                 (self.file("paint_widget_shown.png"), "gui_paint_widget.png")):
                Image.open(source).convert("RGB").quantize(colors=128).save(
                    os.path.join(SOURCE_DIR, "Documentation", "images", name), optimize=True)
        self.assertGreater(foreground_fraction(read_png(png)), MIN_FOREGROUND,
                           "the screen dump is blank")

    def test_solve_diffusion_tables_show_labels_and_column_headers(self):
        # Read from the Qt widgets of the Properties panel (not only a
        # picture): each of the four tables is visible once the advanced
        # properties are on, next to its label, with one column header per
        # number of a row, the texts of the XML's ShowComponentLabels.
        import xml.etree.ElementTree as ET
        root = ET.parse(os.path.join(SOURCE_DIR, "Plugin", "SolveDiffusion.xml")).getroot()
        proxy = next(p for p in root.iter("SourceProxy") if p.get("name") == "SolveDiffusion")
        expected = {}
        for prop in proxy:
            labels = prop.find("Hints/ShowComponentLabels") if prop.find("Hints") is not None \
                else None
            if prop.get("name") in ("PointSources", "PencilBeams", "Detectors", "TimeSnapshots"):
                self.assertIsNotNone(labels, prop.get("name"))
                expected[prop.get("name")] = (prop.get("label"), [
                    c.get("label") for c in sorted(labels, key=lambda c: int(c.get("component")))])
        self.assertEqual(len(expected), 4)
        found = self.results()["panel_tables"]
        self.assertGreaterEqual(found["advanced_boxes"], 1, "no advanced (gear) button found")
        tables = {t["property"]: t for t in found["tables"]}
        for name, (label, headers) in expected.items():
            table = tables[name]
            self.assertTrue(table["found"], name + ": no widget in the panel")
            self.assertTrue(table["visible"], name + ": hidden (advanced properties off?)")
            self.assertEqual(table["label"], label, name + ": its label")
            self.assertTrue(table["header_visible"], name + ": the column headers are hidden")
            self.assertEqual(table["headers"], headers, name + ": the column headers")
        png = found["picture"]
        self.assertTrue(png and os.path.exists(png), "no picture of the tables")
        image = read_png(png)
        width, height = image.GetDimensions()[:2]
        self.assertGreater(width, 200)
        self.assertGreater(height, 200)
        keep_for_inspection(png, "TestParaViewGui_solve_tables.png")
        if UPDATE:
            from PIL import Image
            Image.open(png).convert("RGB").quantize(colors=128).save(
                os.path.join(SOURCE_DIR, "Documentation", "images", "gui_solve_tables.png"),
                optimize=True)

    def test_failed_filter_left_a_clean_empty_output(self):
        results = self.results()
        self.assertEqual(results["failed_output"], {
            "class": "vtkUnstructuredGrid", "points": 0, "cells": 0,
            "has_points_object": True, "point_arrays": [], "cell_arrays": []})
        self.assertEqual(results["radiance_points_failed"], 0)
        self.assertGreater(results["probed_points_before"], 0)
        self.assertGreater(results["probed_points_after"], 0)
        # The repaired chain's surface is the one before the failure (the
        # bunny's boundary points, several hundred at 3,000 tets).
        self.assertGreater(results["radiance_points_before"], 300)
        self.assertEqual(results["radiance_points"], results["radiance_points_before"])
        low, high = results["radiance_range"]
        self.assertGreater(low, 0.0)
        self.assertLess(high, 1.0 / 1.3 ** 2)  # inside the fixed colour range of the picture
        self.assertEqual(results["radiance_readout"], "energy-conserving")  # the default

    def test_render_view_matches_baseline(self):
        png = self.file("render_view.png")
        self.assertTrue(os.path.exists(png), "no screenshot")
        image = read_png(png)
        self.assertEqual(image.GetDimensions()[:2], (640, 480))
        self.assertGreater(foreground_fraction(image), MIN_FOREGROUND, "the picture is blank")
        if UPDATE:
            shutil.copyfile(png, BASELINE)
            print("wrote the baseline %s: look at it before committing" % BASELINE)
            return
        self.assertTrue(os.path.isfile(BASELINE),
                        "no baseline %s: run with --update-baseline" % BASELINE)
        baseline = read_png(BASELINE)
        self.assertEqual(image.GetDimensions(), baseline.GetDimensions())
        difference = vtkImageDifference()
        difference.SetThreshold(PIXEL_THRESHOLD)
        difference.SetInputData(image)
        difference.SetImageData(baseline)
        difference.Update()
        thresholded = difference.GetThresholdedError()
        mean = float(np.mean(np.abs(pixels(image)[:, :3] - pixels(baseline)[:, :3])))
        print("image difference: thresholded error %.3f (tolerance %g), mean %.3f levels "
              "(tolerance %g)" % (thresholded, IMAGE_TOLERANCE, mean, MEAN_TOLERANCE))
        message = ("%s differs from the baseline %s; if the change is intended, look at it "
                   "and update the baseline with --update-baseline"
                   % (keep_for_inspection(png), BASELINE))
        self.assertLessEqual(thresholded, IMAGE_TOLERANCE, message)
        self.assertLessEqual(mean, MEAN_TOLERANCE, message)


if __name__ == "__main__":
    unittest.main(verbosity=2)
