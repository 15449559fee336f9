#!/usr/bin/env python3
"""Tests of translucency.vtkSurfaceReader (PLY, STL, OBJ) and of the CLI on bad surfaces.

How to run (from a build tree):

    PYTHONPATH=<build>/lib/python3.11/site-packages TRANSLUCENCY_SOURCE_DIR=<src> \
        TRANSLUCENCY_CLI=<build>/bin/translucency /usr/bin/python3 TestSurfaceReaders.py

1. Data/bunny.ply read by VTK's vtkPLYReader and by ours: the same points
   (bit for bit, same precision) and the same triangles; both times printed.
2. Round trips: the bunny written by VTK's writers (PLY ascii, binary little
   and big endian; STL ascii and binary; OBJ) and read back by VTK's reader and
   by ours gives the same points and polygons. Hand-written files cover what
   the writers do not produce: extra PLY elements and properties of every type
   (skipped by their sizes), OBJ v/vt/vn corner forms and negative indices.
3. A catalogue of bad files made here from those files (truncations at several
   offsets, counts 0/-1/2^31/2^63/1e10, nan/inf/1e308 coordinates, indices
   -1/out of range/huge, wrong list-count types, non-UTF-8 bytes, duplicated,
   swapped and deleted header lines): each must give a reader error naming
   the file, within 1 s, with an empty output. Random bit flips of the binary
   files must give either such an error or finite points and ids in range.
   The cases found by scripts/mutate_surfaces.py that crashed VTK's readers
   are among them.
4. The CLI: `translucency render --mesh bad.ply --output <existing>` exits
   with status 1 (not a signal), prints the message without a traceback, and
   leaves the existing output files untouched.

Exits non-zero on failure (unittest).
"""

import os
import random
import struct
import subprocess
import sys
import tempfile
import time
import unittest

import numpy as np

import translucency
from vtkmodules.util.misc import calldata_type
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.util.vtkConstants import VTK_STRING
from vtkmodules.vtkIOGeometry import vtkOBJReader, vtkOBJWriter, vtkSTLReader, vtkSTLWriter
from vtkmodules.vtkIOPLY import vtkPLYReader, vtkPLYWriter

SOURCE_DIR = os.environ.get("TRANSLUCENCY_SOURCE_DIR",
                            os.path.join(os.path.dirname(__file__), "..", ".."))
BUNNY = os.path.join(SOURCE_DIR, "Data", "bunny.ply")
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_under_test import find_cli  # noqa: E402

CLI = find_cli("TestSurfaceReaders")


def read_ours(path):
    """(output, errors, seconds) of vtkSurfaceReader on path."""
    reader = translucency.vtkSurfaceReader()
    reader.SetFileName(path)
    errors = []

    @calldata_type(VTK_STRING)
    def on_error(caller, event, message):
        errors.append(message)

    reader.AddObserver("ErrorEvent", on_error)
    reader.GetExecutive().AddObserver("ErrorEvent", lambda *args: None)
    start = time.perf_counter()
    reader.Update()
    return reader.GetOutput(), errors, time.perf_counter() - start


def read_vtk(reader_class, path):
    reader = reader_class()
    reader.SetFileName(path)
    start = time.perf_counter()
    reader.Update()
    return reader.GetOutput(), time.perf_counter() - start


def points_of(poly):
    return vtk_to_numpy(poly.GetPoints().GetData())


def polys_of(poly):
    cells = poly.GetPolys()
    return (vtk_to_numpy(cells.GetOffsetsArray()).astype(np.int64),
            vtk_to_numpy(cells.GetConnectivityArray()).astype(np.int64))


class SurfaceReaderTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls._tmp = tempfile.TemporaryDirectory()
        cls.dir = cls._tmp.name
        cls.bunny, _ = read_vtk(vtkPLYReader, BUNNY)
        cls.files = {"ply_ascii": BUNNY}
        for name, order in (("ply_le", "little"), ("ply_be", "big")):
            path = os.path.join(cls.dir, name + ".ply")
            writer = vtkPLYWriter()
            writer.SetFileTypeToBinary()
            if order == "big":
                writer.SetDataByteOrderToBigEndian()
            else:
                writer.SetDataByteOrderToLittleEndian()
            writer.SetInputData(cls.bunny)
            writer.SetFileName(path)
            writer.Write()
            cls.files[name] = path
        for name, binary in (("stl_ascii", False), ("stl_binary", True)):
            path = os.path.join(cls.dir, name + ".stl")
            writer = vtkSTLWriter()
            if binary:
                writer.SetFileTypeToBinary()
            else:
                writer.SetFileTypeToASCII()
            writer.SetInputData(cls.bunny)
            writer.SetFileName(path)
            writer.Write()
            cls.files[name] = path
        path = os.path.join(cls.dir, "bunny.obj")
        writer = vtkOBJWriter()
        writer.SetInputData(cls.bunny)
        writer.SetFileName(path)
        writer.Write()
        cls.files["obj"] = path

    @classmethod
    def tearDownClass(cls):
        cls._tmp.cleanup()

    def write(self, name, data):
        path = os.path.join(self.dir, name)
        with open(path, "wb") as f:
            f.write(data if isinstance(data, bytes) else data.encode())
        return path

    def assertReads(self, path):
        poly, errors, _ = read_ours(path)
        self.assertEqual(errors, [], "unexpected error reading %s" % path)
        return poly

    def assertSameSurface(self, ours, theirs, exact_points=True):
        self.assertEqual(ours.GetNumberOfPoints(), theirs.GetNumberOfPoints())
        self.assertEqual(ours.GetNumberOfPolys(), theirs.GetNumberOfPolys())
        a, b = points_of(ours), points_of(theirs)
        if exact_points:
            self.assertEqual(a.dtype, b.dtype)
            self.assertTrue(np.array_equal(a, b))
        else:
            self.assertTrue(np.array_equal(a.astype(np.float32), b.astype(np.float32)))
        for x, y in zip(polys_of(ours), polys_of(theirs)):
            self.assertTrue(np.array_equal(x, y))

    # ------------------------------------------------------------ good files
    def test_bunny_same_as_vtk(self):
        # Best of 5 for the times (printed, not asserted).
        theirs, t_vtk = min((read_vtk(vtkPLYReader, BUNNY) for _ in range(5)),
                            key=lambda r: r[1])
        ours, errors, t_ours = min((read_ours(BUNNY) for _ in range(5)), key=lambda r: r[2])
        self.assertEqual(errors, [])
        self.assertEqual(ours.GetNumberOfPoints(), 1839)
        self.assertEqual(ours.GetNumberOfPolys(), 3674)
        self.assertSameSurface(ours, theirs)
        print("Data/bunny.ply: vtkPLYReader %.2f ms, vtkSurfaceReader %.2f ms"
              % (1e3 * t_vtk, 1e3 * t_ours))

    def test_round_trips(self):
        vtk_readers = {"ply": vtkPLYReader, "stl": vtkSTLReader, "obj": vtkOBJReader}
        for name, path in self.files.items():
            with self.subTest(file=name):
                ours = self.assertReads(path)
                theirs, _ = read_vtk(vtk_readers[name[:3]], path)
                # OBJ has no declared precision: ours keeps double, VTK float.
                self.assertSameSurface(ours, theirs, exact_points=not name.startswith("obj"))
                # And the bunny itself (the writers keep float precision, the
                # STL corners are merged back in first-appearance order).
                self.assertEqual(ours.GetNumberOfPolys(), self.bunny.GetNumberOfPolys())
                if name.startswith("ply"):
                    self.assertTrue(np.array_equal(points_of(ours), points_of(self.bunny)))

    def test_ply_skips_other_elements_and_properties(self):
        header = ("ply\nformat {fmt} 1.0\ncomment made by hand\nobj_info none\n"
                  "element vertex 4\nproperty uchar red\nproperty double z\n"
                  "property list ushort float weights\nproperty short x\nproperty int16 y\n"
                  "property float nx\n"
                  "element material 2\nproperty uint id\nproperty list uint8 int8 tags\n"
                  "element face 4\nproperty list uint int32 vertex_index\nproperty char flag\n"
                  "end_header\n")
        coords = [(0, 0, 0.5), (1, 0, 0.25), (0, 1, 0), (0, 0, 1)]
        faces = [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)]
        text = header.format(fmt="ascii")
        for i, (x, y, z) in enumerate(coords):
            text += "%d %r 2 1.5 -2.5 %d %d 0.1\n" % (i, z, x, y)
        text += "7 0\n8 3 -1 2 3\n"
        for f in faces:
            text += "3 %d %d %d -1\n" % f
        for fmt, order in (("binary_little_endian", "<"), ("binary_big_endian", ">")):
            data = header.format(fmt=fmt).encode()
            for i, (x, y, z) in enumerate(coords):
                data += struct.pack(order + "BdHffhhf", i, z, 2, 1.5, -2.5, x, y, 0.1)
            data += struct.pack(order + "IB", 7, 0) + struct.pack(order + "IB3b", 8, 3, -1, 2, 3)
            for f in faces:
                data += struct.pack(order + "I3ib", 3, *f, -1)
            with self.subTest(format=fmt):
                poly = self.assertReads(self.write("extra_%s.ply" % fmt, data))
                self.assertTrue(np.array_equal(points_of(poly), np.array(coords, float)))
                self.assertEqual(points_of(poly).dtype, np.float64)  # a double z
                self.assertTrue(np.array_equal(polys_of(poly)[1], np.ravel(faces)))
        poly = self.assertReads(self.write("extra_ascii.ply", text))
        self.assertTrue(np.array_equal(points_of(poly), np.array(coords, float)))
        self.assertTrue(np.array_equal(polys_of(poly)[1], np.ravel(faces)))

    def test_obj_corner_forms(self):
        text = ("# hand-made\nmtllib none.mtl\no tet\nv 0 0 0\nv 1 0 0 1.0\nv 0 1 0 0.5 0.5 0.5\n"
                "vt 0 0\nvt 1 0\nvn 0 0 1\nv 0 0 1\ns off\ng group\nusemtl x\n"
                "f 1 3 2\nf 1/1 2/2 4/1\nf 2/1/1 3/2/1 4/2/1 # comment\nf -4//-1 -1//1 -2//1\n"
                "f 1 2 3 4\nl 1 2\n")
        poly = self.assertReads(self.write("forms.obj", text))
        self.assertTrue(np.array_equal(points_of(poly),
                                       np.array([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)], float)))
        offsets, ids = polys_of(poly)
        self.assertEqual(list(offsets), [0, 3, 6, 9, 12, 16])
        self.assertEqual(list(ids), [0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2, 0, 1, 2, 3])

    def test_stl_polygons_and_solids(self):
        text = ("solid a\nfacet normal 0 0 -1\nouter loop\nvertex 0 0 0\nvertex 0 1 0\n"
                "vertex 1 1 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid a\n"
                "solid b\n  facet normal nan 0 0\n  outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n"
                "  vertex 0 0 1\n  endloop\n  endfacet\nendsolid\n")
        poly = self.assertReads(self.write("two.stl", text))
        self.assertEqual(poly.GetNumberOfPoints(), 5)  # (0 0 0) and (1 0 0) merged
        self.assertEqual(list(polys_of(poly)[1]), [0, 1, 2, 3, 0, 3, 4])

    # ------------------------------------------------------------- bad files
    def assertFailsNaming(self, name, data, *fragments):
        path = self.write(name, data)
        poly, errors, seconds = read_ours(path)
        self.assertEqual(len(errors), 1, "%s: expected one error, got %r" % (name, errors))
        self.assertIn("'%s'" % path, errors[0])
        for fragment in fragments:
            self.assertIn(fragment, errors[0])
        self.assertLess(seconds, 1.0, "%s took %.2f s" % (name, seconds))
        self.assertEqual(poly.GetNumberOfPoints(), 0)
        return errors[0]

    def assertCleanOrValid(self, name, data):
        path = self.write(name, data)
        poly, errors, seconds = read_ours(path)
        self.assertLess(seconds, 1.0, "%s took %.2f s" % (name, seconds))
        if errors:
            self.assertIn("'%s'" % path, errors[0])
            return False
        xyz = points_of(poly) if poly.GetNumberOfPoints() else np.zeros((0, 3))
        self.assertTrue(np.all(np.isfinite(xyz)), name)
        offsets, ids = polys_of(poly)
        self.assertTrue(np.all((ids >= 0) & (ids < poly.GetNumberOfPoints())), name)
        self.assertTrue(np.all(np.diff(offsets) >= 3), name)
        return True

    def bytes_of(self, key):
        with open(self.files[key], "rb") as f:
            return f.read()

    def test_truncated(self):
        for key in self.files:
            data = self.bytes_of(key)
            for fraction in (0.0, 0.001, 0.01, 0.1, 0.5, 0.9, 0.99):
                cut = int(fraction * len(data))
                with self.subTest(file=key, cut=cut):
                    if key == "obj" or (key == "ply_ascii" and fraction == 0.99):
                        # Cut at a line end, an OBJ (or the last face line of
                        # an ASCII PLY cut mid-number) can still be a valid file.
                        self.assertCleanOrValid("cut_%s_%d.%s" % (key, cut, key[:3]), data[:cut])
                    else:
                        self.assertFailsNaming("cut_%s_%d.%s" % (key, cut, key[:3]), data[:cut])
            if key.startswith(("ply_le", "ply_be", "stl_binary")):
                with self.subTest(file=key, cut="1 byte short"):
                    self.assertFailsNaming("short_%s.%s" % (key, key[:3]), data[:-1])

    def header_cases(self):
        """(name, header edit) pairs that must all fail, for each PLY encoding."""
        count_cases = []
        for element in ("vertex", "face"):
            for bad in ("-1", "2147483648", "9223372036854775808", "1e10",
                        "18446744073709551616", "900000000", "x"):
                count_cases.append(("%s_count_%s" % (element, bad),
                                    lambda lines, e=element, b=bad: [
                                        "element %s %s" % (e, b) if l.startswith("element " + e)
                                        else l for l in lines]))
            if element == "vertex":
                count_cases.append(("vertex_count_0", lambda lines: [
                    "element vertex 0" if l.startswith("element vertex") else l for l in lines]))
        count_cases.append(("face_count_0", lambda lines: [
            "element face 0" if l.startswith("element face") else l for l in lines]))

        def swap(a, b):
            def edit(lines):
                lines = list(lines)
                i = next(k for k, l in enumerate(lines) if l.startswith(a))
                j = next(k for k, l in enumerate(lines) if l.startswith(b))
                lines[i], lines[j] = lines[j], lines[i]
                return lines
            return edit

        def delete(prefix):
            return lambda lines: [l for l in lines if not l.startswith(prefix)]

        def duplicate(prefix):
            def edit(lines):
                k = next(k for k, l in enumerate(lines) if l.startswith(prefix))
                return lines[:k + 1] + lines[k:]
            return edit

        def replace(old, new):
            return lambda lines: [l.replace(old, new) for l in lines]

        return count_cases + [
            ("list_count_float", replace("list uchar", "list float")),
            ("list_count_double", replace("list uchar", "list double")),
            ("list_index_float", replace("uchar int vertex", "uchar float vertex")),
            ("list_unknown_type", replace("uchar int vertex", "uchar int128 vertex")),
            ("swap_ply_format", swap("ply", "format")),
            ("swap_element_property", swap("element vertex", "property float x")),
            ("duplicate_element", duplicate("element vertex")),
            ("duplicate_property", duplicate("property float y")),
            ("duplicate_format", duplicate("format")),
            ("duplicate_end_header", duplicate("end_header")),
            ("delete_format", delete("format")),
            ("delete_x", delete("property float x")),
            ("delete_z", delete("property float z")),
            ("delete_vertex_element", delete("element vertex")),
            ("delete_face_list", delete("property list")),
            ("delete_end_header", delete("end_header")),
            ("non_utf8_keyword", lambda lines: [lines[0], "\udcff\udcfeelement x 1"] + lines[1:]),
            ("format_version", replace("1.0", "2.0")),
        ]

    def test_ply_header_catalogue(self):
        for key in ("ply_ascii", "ply_le", "ply_be"):
            data = self.bytes_of(key)
            end = data.index(b"end_header\n") + len(b"end_header\n")
            lines = data[:end].decode("ascii").splitlines()
            for name, edit in self.header_cases():
                header = ("\n".join(edit(lines)) + "\n").encode("utf-8", "surrogateescape")
                with self.subTest(file=key, case=name):
                    self.assertFailsNaming("%s_%s.ply" % (key, name), header + data[end:])

    def test_ply_ascii_values(self):
        with open(BUNNY, "rb") as f:
            head, body = f.read().decode("ascii").split("end_header\n")
        lines = body.splitlines()
        first_face = 1839
        cases = {
            "nan": (0, "nan 0.367866 7.65018", "not a finite number"),
            "inf": (0, "3.9 inf 7.65018", "not a finite number"),
            "minus_inf": (5, "3.9 0.3 -inf", "not a finite number"),
            "1e308_float": (0, "1e308 0.367866 7.65018", "out of the range of its type 'float'"),
            "1e999": (0, "1e999 0.367866 7.65018", "out of the range"),
            "garbage": (7, "3.9 0.3 seven", "not a number"),
            "two_values": (7, "3.9 0.3", "line ends before property 'z'"),
            "four_values": (7, "3.9 0.3 1 1", "values more than the header declares"),
            "non_utf8": (3, "3.9 0.3 \udcff\udcfe", "not a number"),
            "index_minus_1": (first_face, "3 -1 1 2", "out of range [0, 1839)"),
            "index_n": (first_face + 3, "3 0 1 1839", "out of range [0, 1839)"),
            "index_huge": (first_face, "3 0 1 4294967296", "out of the range of its type 'int'"),
            "index_float": (first_face, "3 0 1 2.5", "not an integer"),
            "count_2": (first_face + 1, "2 0 1", "needs at least 3"),
            "count_0": (first_face + 1, "0", "needs at least 3"),
            "count_4": (first_face + 1, "4 0 1 2", "line holds only 3"),
            "count_minus_1": (first_face + 1, "-1 0 1 2", "out of the range of its type 'uchar'"),
            "count_256": (first_face + 1, "256 0 1 2", "out of the range of its type 'uchar'"),
            "extra_line": (len(lines), "1 2 3", "data after the last element"),
        }
        for name, (index, text, message) in cases.items():
            edited = list(lines)
            if index == len(lines):
                edited.append(text)
            else:
                edited[index] = text
            content = (head + "end_header\n" + "\n".join(edited) + "\n").encode(
                "utf-8", "surrogateescape")
            with self.subTest(case=name):
                self.assertFailsNaming("ascii_%s.ply" % name, content, message)

    def test_ply_binary_values(self):
        for key, order in (("ply_le", "<"), ("ply_be", ">")):
            data = self.bytes_of(key)
            end = data.index(b"end_header\n") + len(b"end_header\n")
            faces = end + 12 * 1839
            cases = {
                "nan": (end, struct.pack(order + "f", float("nan")), "non-finite"),
                "inf": (end + 4, struct.pack(order + "f", float("inf")), "non-finite"),
                "index_minus_1": (faces + 1, struct.pack(order + "i", -1), "out of range"),
                "index_n": (faces + 5, struct.pack(order + "i", 1839), "out of range"),
                "index_huge": (faces + 9, struct.pack(order + "i", 2**31 - 1), "out of range"),
                "count_2": (faces, b"\x02", "needs at least 3"),
                "count_255": (faces, b"\xff", "byte offset"),
                "count_0": (faces + 13, b"\x00", "needs at least 3"),
            }
            for name, (offset, patch, message) in cases.items():
                content = data[:offset] + patch + data[offset + len(patch):]
                with self.subTest(file=key, case=name):
                    self.assertFailsNaming("%s_%s.ply" % (key, name), content, message)
            # A binary header claiming 9e8 vertices in a 1 KB file: at once.
            small = data[:end].replace(b"element vertex 1839", b"element vertex 900000000")
            small += data[end:end + 1024]
            self.assertFailsNaming("%s_9e8.ply" % key, small, "900000000", "bytes are left")

    def test_stl_catalogue(self):
        binary = self.bytes_of("stl_binary")
        cases = {
            "count_0": binary[:80] + struct.pack("<I", 0) + binary[84:],
            "count_minus_1": binary[:80] + struct.pack("<I", 2**32 - 1) + binary[84:],
            "count_2^31": binary[:80] + struct.pack("<I", 2**31) + binary[84:],
            "count_plus_1": binary[:80] + struct.pack("<I", 3675) + binary[84:],
            "nan": binary[:96] + struct.pack("<f", float("nan")) + binary[100:],
            "inf": binary[:100] + struct.pack("<f", float("-inf")) + binary[104:],
            "short": binary[:50],
            "empty": b"",
        }
        for name, content in cases.items():
            with self.subTest(case=name):
                self.assertFailsNaming("binary_%s.stl" % name, content)
        text = self.bytes_of("stl_ascii").decode("ascii")
        lines = text.splitlines()
        vertex = next(k for k, l in enumerate(lines) if l.strip().startswith("vertex"))
        text_cases = {
            "nan": (vertex, "vertex nan 0 0", "not a finite number"),
            "inf": (vertex, "vertex 0 inf 0", "not a finite number"),
            "1e39": (vertex, "vertex 0 0 1e39", "out of the range of a float"),
            "garbage": (vertex, "vertex 1 2 three", "not a number"),
            "two_corners": (vertex + 2, "endloop", "needs at least 3"),
            "no_endloop": (vertex + 3, "endfacet", "expected 'vertex"),
            "non_utf8": (vertex + 1, "vertex \udcff 1 2", "'?' is not a number"),
            "no_solid": (0, "solids", "expected 'solid'"),
            "no_endsolid": (len(lines) - 1, "", "truncated"),
        }
        for name, (index, line, message) in text_cases.items():
            edited = list(lines)
            edited[index] = line
            content = ("\n".join(edited) + "\n").encode("utf-8", "surrogateescape")
            with self.subTest(case=name):
                self.assertFailsNaming("ascii_%s.stl" % name, content, message)

    def test_obj_catalogue(self):
        good = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n"
        cases = {
            "index_0": ("f 0 3 2", "non-zero"),
            "index_minus_1_first": ("f -5 1 2", "reaches before the first"),
            "index_out_of_range": ("f 1 2 5", "refers to vertex 5 but the file defines 4"),
            "index_huge": ("f 1 2 9223372036854775807", "the file defines 4"),
            "index_too_big": ("f 1 2 99999999999999999999", "bad corner"),
            "two_corners": ("f 1 2", "needs at least 3"),
            "four_parts": ("f 1/1/1/1 2 3", "bad corner"),
            "trailing_slash": ("f 1/ 2 3", "bad corner"),
            "vt_out_of_range": ("f 1/1 2/1 3/1", "texture coordinate 1 but the file defines 0"),
            "vn_out_of_range": ("f 1//2 2//2 3//2", "normal 2 but the file defines 0"),
            "v_nan": ("v nan 0 0", "not a finite number"),
            "v_inf": ("v 0 -inf 0", "not a finite number"),
            "v_1e999": ("v 0 0 1e999", "out of the range of a double"),
            "v_two_values": ("v 1 2", "needs 3 coordinates"),
            "v_garbage": ("v 1 2 x", "not a number"),
            "v_non_utf8": ("v 1 2 \udcff", "not a number"),
            "vn_nan": ("vn nan 0 0", "not a finite number"),
        }
        for name, (line, message) in cases.items():
            content = (good + line + "\n").encode("utf-8", "surrogateescape")
            if line.startswith("v "):
                content = (line + "\n" + good).encode("utf-8", "surrogateescape")
            with self.subTest(case=name):
                self.assertFailsNaming("%s.obj" % name, content, message)

    def test_bit_flips(self):
        rng = random.Random(21)
        for key in ("ply_le", "ply_be", "stl_binary", "ply_ascii"):
            data = bytearray(self.bytes_of(key))
            errors = 0
            for case in range(40):
                flipped = bytearray(data)
                for _ in range(rng.randint(1, 4)):
                    flipped[rng.randrange(len(flipped))] ^= 1 << rng.randrange(8)
                with self.subTest(file=key, case=case):
                    if not self.assertCleanOrValid("flip_%s_%d.%s" % (key, case, key[:3]),
                                                   bytes(flipped)):
                        errors += 1
            print("%s: %d of 40 bit-flipped files rejected, the others read valid" % (key, errors))

    def test_missing_and_unknown(self):
        poly, errors, _ = read_ours(os.path.join(self.dir, "missing.ply"))
        self.assertTrue(errors and "does not exist" in errors[0])
        path = self.write("surface.off", "OFF\n")
        poly, errors, _ = read_ours(path)
        self.assertTrue(errors and "unknown surface format" in errors[0])
        reader = translucency.vtkSurfaceReader()
        self.assertEqual(reader.CanReadFile(BUNNY), 1)
        self.assertEqual(reader.CanReadFile(path), 0)
        self.assertEqual(reader.CanReadFile(self.dir + "/x.PLY"), 0)  # no such file

    # ------------------------------------------------------------------ CLI
    def test_cli_bad_surfaces(self):
        prefix = os.path.join(self.dir, "out", "result")
        os.makedirs(os.path.dirname(prefix), exist_ok=True)
        existing = {}
        for ext in (".vtu", ".vtp", ".json"):
            with open(prefix + ext, "w") as f:
                f.write("precious " + ext)
            existing[prefix + ext] = "precious " + ext
        binary = self.bytes_of("ply_le")
        end = binary.index(b"end_header\n") + len(b"end_header\n")
        with open(BUNNY, "rb") as f:
            ascii_bunny = f.read()
        tet = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n"
        cases = {
            "vertices_9e8.ply": (binary[:end].replace(b"vertex 1839", b"vertex 900000000") +
                                 binary[end:end + 1024], "900000000"),
            "nan.ply": (ascii_bunny.replace(b"3.90569 0.367866", b"nan 0.367866", 1),
                        "not a finite number"),
            "index.ply": (ascii_bunny.replace(b"\n3 ", b"\n3 -1 ", 1), "out of range"),
            "truncated.stl": (self.bytes_of("stl_binary")[:5000], "truncated"),
            "face.obj": (tet.replace("f 2 3 4", "f 2 3 40"), "refers to vertex 40"),
            # Read fine, rejected by vtkTetrahedralizeSurface before VTK's cleaning.
            "huge.obj": (tet.replace("v 0 1 0", "v 0 1e200 0"), "magnitude"),
            # Found by scripts/mutate_surfaces.py: a duplicated 'v' line shifts
            # every vertex by one, a surface crossing itself everywhere, on
            # which TetGen's -d pass ran for minutes (a hang at the CLI).
            "shifted.obj": (self.bytes_of("obj").replace(b"\nv ", b"\nv 1 2 3\nv ", 1),
                            "intersects itself"),
        }
        for name, (content, message) in cases.items():
            path = self.write(name, content)
            with self.subTest(case=name):
                result = subprocess.run(
                    [CLI, "render", "--mesh", path, "--target-tets", "500", "--output", prefix,
                     "--json", prefix + ".json"],
                    capture_output=True, text=True, timeout=60)
                # The bad file is refused within seconds, not after TetGen's minutes.
                self.assertEqual(result.returncode, 1, result.stderr)
                self.assertIn(message, result.stderr)
                self.assertIn(path, result.stderr)
                self.assertNotIn("Traceback", result.stderr)
                self.assertNotIn("returned failure", result.stderr)
                for out, text in existing.items():
                    with open(out) as f:
                        self.assertEqual(f.read(), text, "%s was changed" % out)


if __name__ == "__main__":
    unittest.main(verbosity=1)
