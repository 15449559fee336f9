#!/usr/bin/env python3
"""Bad mesh and JSON inputs through the `translucency` command line (issue 21).

How to run (from a build tree; ctest sets the variables itself):

    TRANSLUCENCY_CLI=<build>/bin/translucency /usr/bin/python3 TestBadMeshInputs.py

A catalogue of generated bad .vtu / .vtp / material-table / material / paint /
scene files, each run through the CLI in a subprocess under a time limit.
Each case asserts:
  - no signal (crash) and no time-out (hang);
  - a non-zero exit with a message naming the file and the problem (the
    element and attribute of a VTK XML file, the cell id of a bad cell, the
    nesting limit of a deep JSON value), short enough (a bad value is cut);
  - the existing output files (PREFIX.vtu, PREFIX.vtp, the JSON report) are
    untouched and no temporary is left behind.
Then: a good mesh with two coincident points that both carry tets renders
with a warning naming the points; a face shared by three tets fails with the
core's whole message (it contains "): ", which MessageCollector::Last() once
cut at); a folder planted at the old fixed temporary name PREFIX.vtp.part
does not block the write (the temporaries are unique); VTK-written .vtu/.vtp in every data mode and compressor pass the
pre-validation.

Exits non-zero on failure (unittest).
"""

import json
import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_under_test import find_cli  # noqa: E402

CLI = find_cli("TestBadMeshInputs")
TIME_LIMIT = 60  # seconds per run; the good cases take well under one

# A 2 x 2 x 2 block of 5 mm cubes, each in 6 tets: 27 points, 48 tets.
GRID_POINTS = [(5.0 * i, 5.0 * j, 5.0 * k) for k in range(3) for j in range(3) for i in range(3)]


def _cube_tets():
    def pid(i, j, k):
        return i + 3 * j + 9 * k

    tets = []
    for k in range(2):
        for j in range(2):
            for i in range(2):
                v = [pid(i + a, j + b, k + c) for c in (0, 1) for b in (0, 1) for a in (0, 1)]
                # Kuhn split of the cube along the diagonal v0-v7.
                for path in ((1, 3), (1, 5), (2, 3), (2, 6), (4, 5), (4, 6)):
                    a, b = path
                    tets.append([v[0], v[a], v[a | b], v[7]])
    return tets


GRID_TETS = _cube_tets()


def vtu_text(points=GRID_POINTS, cells=GRID_TETS, types=None, piece=None, points_attrs="",
             coord_text=None):
    """An ascii .vtu; `piece` overrides the <Piece> attributes."""
    types = types if types is not None else [10] * len(cells)
    offsets, end = [], 0
    for c in cells:
        end += len(c)
        offsets.append(end)
    piece = piece if piece is not None else \
        'NumberOfPoints="%d" NumberOfCells="%d"' % (len(points), len(cells))
    coords = coord_text if coord_text is not None else \
        " ".join("%r %r %r" % tuple(p) for p in points)
    return (
        '<?xml version="1.0"?>\n'
        '<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian" '
        'header_type="UInt32">\n'
        '  <UnstructuredGrid>\n'
        '    <Piece %s>\n'
        '      <CellData>\n'
        '        <DataArray type="Int32" Name="Ids" format="ascii">%s</DataArray>\n'
        '      </CellData>\n'
        '      <Points>\n'
        '        <DataArray type="Float64" Name="Points" NumberOfComponents="3" '
        'format="ascii"%s>\n          %s\n        </DataArray>\n'
        '      </Points>\n'
        '      <Cells>\n'
        '        <DataArray type="Int64" Name="connectivity" format="ascii">\n          %s\n'
        '        </DataArray>\n'
        '        <DataArray type="Int64" Name="offsets" format="ascii">\n          %s\n'
        '        </DataArray>\n'
        '        <DataArray type="UInt8" Name="types" format="ascii">\n          %s\n'
        '        </DataArray>\n'
        '      </Cells>\n'
        '    </Piece>\n'
        '  </UnstructuredGrid>\n'
        '</VTKFile>\n'
    ) % (piece, " ".join("0" for _ in cells), points_attrs, coords, " ".join(str(i) for c in cells for i in c),
         " ".join(map(str, offsets)), " ".join(map(str, types)))


def appended_vtu(data_bytes_claim):
    """A .vtu whose appended raw points claim `data_bytes_claim` bytes."""
    import struct
    head = (
        '<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="0.1" '
        'byte_order="LittleEndian" header_type="UInt32">\n<UnstructuredGrid>\n'
        '<Piece NumberOfPoints="4" NumberOfCells="1">\n<Points>\n'
        '<DataArray type="Float64" Name="Points" NumberOfComponents="3" format="appended" '
        'offset="0"/>\n</Points>\n<Cells>\n'
        '<DataArray type="Int64" Name="connectivity" format="ascii">0 1 2 3</DataArray>\n'
        '<DataArray type="Int64" Name="offsets" format="ascii">4</DataArray>\n'
        '<DataArray type="UInt8" Name="types" format="ascii">10</DataArray>\n'
        '</Cells>\n</Piece>\n</UnstructuredGrid>\n<AppendedData encoding="raw">\n_'
    ).encode()
    body = struct.pack("<I", data_bytes_claim) + struct.pack(
        "<12d", 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1)
    return head + body + b"\n</AppendedData>\n</VTKFile>\n"


def deep_json(depth, key="absorption"):
    return '{"%s": %s1%s}' % (key, "[" * depth, "]" * depth)


SENTINEL = b"old output, must survive\n"


class BadMeshInputs(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.dir = cls.tmp.name

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def write(self, name, content):
        path = os.path.join(self.dir, name)
        with open(path, "wb") as f:
            f.write(content.encode() if isinstance(content, str) else content)
        return path

    def run_cli(self, args, case, ignore=()):
        """Run the CLI with outputs over sentinel files; assert no crash, no
        hang, and untouched outputs. Returns (returncode, stderr)."""
        out = os.path.join(self.dir, "out_" + case)
        outputs = [out + ".vtu", out + ".vtp", out + ".json"]
        for p in outputs:
            with open(p, "wb") as f:
                f.write(SENTINEL)
        try:
            proc = subprocess.run([CLI] + args + ["--output", out, "--json", out + ".json"],
                                  capture_output=True, timeout=TIME_LIMIT)
        except subprocess.TimeoutExpired:
            self.fail("%s: no answer within %d s (hang)" % (case, TIME_LIMIT))
        stderr = proc.stderr.decode("utf-8", "replace")
        self.assertGreaterEqual(proc.returncode, 0,
                                "%s: killed by signal %d\n%s" % (case, -proc.returncode, stderr))
        if proc.returncode != 0:
            for p in outputs:
                with open(p, "rb") as f:
                    self.assertEqual(f.read(), SENTINEL, "%s: %s was changed" % (case, p))
        leftovers = [n for n in os.listdir(self.dir) if n.startswith("out_" + case) and
                     (n.endswith(".part") or ".tmp" in n) and n not in ignore]
        self.assertEqual(leftovers, [], case)
        return proc.returncode, stderr

    def expect_error(self, case, args, *needles, ignore=()):
        code, stderr = self.run_cli(args, case, ignore)
        self.assertNotEqual(code, 0, "%s: exit 0\n%s" % (case, stderr))
        self.assertIn("error", stderr, case)
        for needle in needles:
            self.assertIn(needle, stderr, "%s: %r not in\n%s" % (case, needle, stderr))
        self.assertLess(len(stderr), 2000, "%s: the message is not cut:\n%s" % (case, stderr[:300]))

    # -- VTK XML files --------------------------------------------------------
    def test_xml_catalogue(self):
        good = vtu_text()
        one_id = [list(GRID_TETS[0][:1])] + GRID_TETS[1:]
        middle = GRID_TETS[:20] + [GRID_TETS[20][:3]] + GRID_TETS[21:]
        catalogue = [
            ("components_2e31", good.replace('NumberOfComponents="3"',
                                             'NumberOfComponents="2147483648"'),
             ["NumberOfComponents", "out of range", "<DataArray Name=\"Points\">"]),
            ("tuples_minus1", good.replace('NumberOfComponents="3"',
                                           'NumberOfComponents="3" NumberOfTuples="-1"'),
             ["NumberOfTuples", "out of range"]),
            ("cells_minus1", vtu_text(piece='NumberOfPoints="27" NumberOfCells="-1"'),
             ["<Piece>", "NumberOfCells", "out of range"]),
            ("points_1e10", vtu_text(piece='NumberOfPoints="10000000000" NumberOfCells="48"'),
             ["NumberOfPoints", "out of range"]),
            ("points_float", vtu_text(piece='NumberOfPoints="1e10" NumberOfCells="48"'),
             ["NumberOfPoints", "not an integer"]),
            ("points_more", vtu_text(piece='NumberOfPoints="28" NumberOfCells="48"'),
             ["Points", "81 ascii values", "84"]),
            ("bad_type", good.replace('type="Float64"', 'type="Float33"'), ["Float33"]),
            ("bad_format", good.replace('format="ascii"', 'format="weird"', 1), ["weird"]),
            ("wrong_kind", good.replace('type="UnstructuredGrid"', 'type="PolyData"'),
             ["<VTKFile>", "UnstructuredGrid"]),
            ("truncated", good[:len(good) // 2], ["truncated"]),
            ("empty", "", ["empty"]),
            ("not_xml", "hello world\n", ["not a VTK XML file"]),
            ("deep_xml", good.replace("<Points>", "<Points>" + "<X>" * 100000, 1),
             ["nested deeper"]),
            ("appended_huge", appended_vtu(0xFFFFFFF0), ["Points", "4294967280 bytes"]),
            ("appended_truncated", appended_vtu(96)[:-60], ["truncated"]),
            ("tet_one_id", vtu_text(cells=one_id), ["cell 0", "1 point ids"]),
            ("tet_short_middle", vtu_text(cells=middle), ["cell 20", "3 point ids"]),
            ("id_out_of_range", vtu_text(cells=[[0, 1, 2, 99]] + GRID_TETS[1:]),
             ["cell 0", "point id 99"]),
            ("id_negative", vtu_text(cells=[[0, 1, 2, -5]] + GRID_TETS[1:]),
             ["cell 0", "point id -5"]),
            ("not_tet", vtu_text(types=[10] * 47 + [9]), ["cell 47", "vtkQuad"]),
            ("nan_point", vtu_text(coord_text=" ".join(
                "nan" if n == 4 else "%r" % c for n, c in
                enumerate(x for p in GRID_POINTS for x in p))),
             ["point 1", "non-finite"]),
        ]
        for case, text, needles in catalogue:
            with self.subTest(case=case):
                path = self.write(case + ".vtu", text)
                self.expect_error(case, ["render", "--mesh", path], path, *needles)

    def test_vtp_catalogue(self):
        sphere = self.vtk_sphere_ascii()
        catalogue = [
            ("vtp_polys_minus1", sphere.replace('NumberOfPolys="', 'NumberOfPolys="-1" x="', 1),
             ["NumberOfPolys", "out of range"]),
            ("vtp_points_huge", sphere.replace('NumberOfPoints="', 'NumberOfPoints="9', 1),
             ["<DataArray Name=\"Normals\">", "ascii values"]),
            ("vtp_components", sphere.replace('NumberOfComponents="3"',
                                              'NumberOfComponents="0"', 1),
             ["NumberOfComponents", "out of range"]),
            ("vtp_as_vtu", vtu_text(), ["<VTKFile>", "PolyData"]),
            # Mutation loop, seed 2 case 75: vtkStaticCleanPolyData crashed (SIGSEGV).
            ("vtp_id_out_of_range", self.polygon_id(sphere, 4194316),
             ["polygon 0 uses point id 4194316"]),
        ]
        for case, text, needles in catalogue:
            with self.subTest(case=case):
                path = self.write(case + ".vtp", text)
                self.expect_error(case, ["render", "--mesh", path], path, *needles)

    @staticmethod
    def polygon_id(sphere, new_id):
        """The ascii sphere with the first id of its first polygon replaced."""
        start = sphere.index('Name="connectivity"', sphere.index("<Polys>"))
        body = sphere.index(">", start) + 1
        rest = sphere[body:].lstrip()
        first = rest.split()[0]
        return sphere[:body] + " " + str(new_id) + rest[len(first):]

    def vtk_sphere_ascii(self):
        from vtkmodules.vtkFiltersSources import vtkSphereSource
        from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter
        s = vtkSphereSource()
        s.SetRadius(5)
        s.SetThetaResolution(8)
        s.SetPhiResolution(8)
        w = vtkXMLPolyDataWriter()
        w.SetInputConnection(s.GetOutputPort())
        w.SetDataModeToAscii()
        w.SetFileName(os.path.join(self.dir, "sphere_ascii.vtp"))
        w.Write()
        with open(os.path.join(self.dir, "sphere_ascii.vtp")) as f:
            text = f.read()
        self.assertIn('NumberOfPolys="', text)
        return text

    def test_vtk_written_files_pass(self):
        """Every data mode, header type and compressor VTK writes passes the
        pre-validation and renders."""
        from vtkmodules.vtkFiltersSources import vtkSphereSource
        from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter, vtkXMLUnstructuredGridReader, \
            vtkXMLUnstructuredGridWriter
        grid_path = self.write("good.vtu", vtu_text())
        r = vtkXMLUnstructuredGridReader()
        r.SetFileName(grid_path)
        r.Update()
        sphere = vtkSphereSource()
        sphere.SetRadius(5)
        sphere.Update()
        for mode in (0, 1, 2):
            for comp in ("none", "zlib", "lz4", "lzma"):
                for header64 in ((False, True) if comp == "zlib" else (False,)):
                    for W, data, ext in ((vtkXMLUnstructuredGridWriter, r.GetOutput(), "vtu"),
                                         (vtkXMLPolyDataWriter, sphere.GetOutput(), "vtp")):
                        case = "ok_%d_%s_%d_%s" % (mode, comp, header64, ext)
                        with self.subTest(case=case):
                            w = W()
                            w.SetInputData(data)
                            path = os.path.join(self.dir, case + "." + ext)
                            w.SetFileName(path)
                            w.SetDataMode(mode)
                            getattr(w, {"none": "SetCompressorTypeToNone",
                                        "zlib": "SetCompressorTypeToZLib",
                                        "lz4": "SetCompressorTypeToLZ4",
                                        "lzma": "SetCompressorTypeToLZMA"}[comp])()
                            if header64:
                                w.SetHeaderTypeToUInt64()
                            w.SetEncodeAppendedData(mode == 2 and comp == "none")
                            self.assertEqual(w.Write(), 1)
                            code, stderr = self.run_cli(
                                ["render", "--mesh", path, "--target-tets", "300"], case)
                            self.assertEqual(code, 0, "%s\n%s" % (case, stderr))

    # -- the tet mesh: cracks and shared faces --------------------------------
    def test_coincident_points_warn(self):
        # Point 27 duplicates point 13 (the centre); the tets of one cube use it.
        points = GRID_POINTS + [GRID_POINTS[13]]
        tets = [[27 if i == 13 else i for i in t] if n < 6 else t for n, t in enumerate(GRID_TETS)]
        path = self.write("crack.vtu", vtu_text(points=points, cells=tets))
        code, stderr = self.run_cli(["render", "--mesh", path], "crack")
        self.assertEqual(code, 0, stderr)
        self.assertIn("warning", stderr)
        self.assertIn("13 and 27", stderr)
        self.assertIn("coincident", stderr)

    def test_whole_core_message_survives(self):
        # A face shared by three tets: the core's message holds "): ".
        points = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (0, 0, -1), (0.3, 0.3, 1)]
        tets = [[0, 1, 2, 3], [0, 2, 1, 4], [0, 1, 2, 5]]
        path = self.write("shared_face.vtu", vtu_text(points=points, cells=tets))
        self.expect_error("shared_face", ["render", "--mesh", path],
                          "is shared by 3 tets (tet 0, tet 1, tet 2): a face can belong to at "
                          "most two tets")

    # -- output files: all new or all old -------------------------------------
    def test_planted_temporary_name_does_not_block(self):
        # The temporaries have unique names created exclusively (issue 34): a
        # folder at the old fixed name PREFIX.vtp.part no longer blocks the
        # write. (A failed write keeping the old outputs: Python.TestUserFiles,
        # with the file-size limit of the process.)
        good = self.write("good_for_write.vtu", vtu_text())
        out = os.path.join(self.dir, "out_blocked")
        os.mkdir(out + ".vtp.part")
        try:
            code, stderr = self.run_cli(["render", "--mesh", good], "blocked",
                                        ignore=("out_blocked.vtp.part",))
        finally:
            os.rmdir(out + ".vtp.part")
        self.assertEqual(code, 0, stderr)
        # All three are replaced together.
        self.assertEqual(code, 0, stderr)
        for ext in (".vtu", ".vtp", ".json"):
            with open(out + ext, "rb") as f:
                self.assertNotEqual(f.read(), SENTINEL, ext)

    # -- JSON inputs -------------------------------------------------------------
    def test_json_catalogue(self):
        mesh = self.write("json_mesh.vtu", vtu_text())
        huge = "x" * 100000
        catalogue = [
            ("material_deep", "material.json", deep_json(100000),
             ["--material"], ["nested deeper than 64"]),
            ("material_huge_string", "material.json",
             '{"absorption": "%s", "reduced_scattering": [1,1,1]}' % huge,
             ["--material"], ["absorption"]),
            ("table_deep", "table.json",
             '{"materials": [{"name": "a", "id": 0, "absorption": %s1%s}]}' %
             ("[" * 100000, "]" * 100000), ["--material-ids", "Ids", "--material"],
             ["nested deeper than 64"]),
            ("table_huge_value", "table.json",
             '{"materials": [{"name": "a", "id": "%s"}]}' % huge,
             ["--material-ids", "Ids", "--material"], ["\"id\" must be", "..."]),
            ("paint_deep", "paint.json", deep_json(100000, "points"), ["--paint"],
             ["nested deeper than 64"]),
            ("stroke_deep", "stroke.json", deep_json(100000, "points"), ["--cut-stroke"],
             ["nested deeper than 64"]),
            # Mutation loop, seed 2 case 35: exit 0 with a NaN fluence.
            ("material_1e308", "material.json",
             '{"absorption": [0.01, 1e308, 0.03], "reduced_scattering": [1, 1, 1]}',
             ["--material"], ['"absorption"[1] must be at most 1e+06 1/mm']),
            ("table_1e308", "table.json",
             '{"materials": [{"name": "a", "id": 0, "absorption": [1e308, 0, 0], '
             '"reduced_scattering": [1, 1, 1]}]}', ["--material-ids", "Ids", "--material"],
             ['"absorption"[0] must be finite, >= 0 and <= 1e6']),
            # Mutation loop, seed 1 cases 364 and 1632: exit 0 with a NaN fluence.
            ("material_eta_denormal", "material.json",
             '{"absorption": [0.01, 0.02, 0.03], "reduced_scattering": [1, 1, 1], '
             '"refractive_index": 1e-320}', ["--material"],
             ['"refractive_index" must be in [0.1, 10]']),
            ("table_eta_denormal", "table.json",
             '{"materials": [{"name": "a", "id": 0, "absorption": [0, 0, 0], '
             '"reduced_scattering": [1, 1, 1], "refractive_index": 1e-320}]}',
             ["--material-ids", "Ids", "--material"],
             ['"refractive_index" must be in [0.1, 10]']),
            # Mutation loop, seed 1 case 2620: exit 0 with a NaN fluence.
            ("paint_1e308", "paint.json",
             '{"points": [[0, 0, 10], [10, 10, 10]], "width": 2, "mode": "set", '
             '"absorption": [1e308, 0.2, 0.3], "reduced_scattering": [2, 2, 2]}', ["--paint"],
             ['"absorption"[0] must be within +-1e+06']),
            ("material_not_json", "material.json", '{"absorption": [1, 2,', ["--material"],
             ["not valid JSON"]),
        ]
        for case, name, text, option, needles in catalogue:
            with self.subTest(case=case):
                path = self.write(case + "_" + name, text)
                args = ["render", "--mesh", mesh] + option + [path]
                self.expect_error(case, args, path, *needles)

    def test_scene_huge_number(self):
        # Mutation loop, seed 2 case 38: the ray caster crashed (SIGSEGV) on a
        # box up to z = 1e308.
        scene = {"cell_size": 6, "objects": [
            {"name": "room", "type": "box", "min": [0, 0, 0], "max": [30, 30, 1e308],
             "inward": True, "open_face": "-y"},
            {"name": "block", "type": "box", "translucent": True, "min": [10, 10, 0.05],
             "max": [18, 18, 8], "material": "marble", "max_tet_volume": 8}],
            "lights": [{"type": "point", "position": [15, 15, 28], "power": [500, 500, 500]}]}
        path = self.write("scene_huge.json", json.dumps(scene))
        proc = subprocess.run([CLI, "radiosity", "--scene", path, "--output",
                               os.path.join(self.dir, "scene_huge_out")],
                              capture_output=True, timeout=TIME_LIMIT)
        stderr = proc.stderr.decode("utf-8", "replace")
        self.assertGreater(proc.returncode, 0, stderr)
        self.assertIn(path, stderr)
        self.assertIn("'room': \"max\" holds 1e+308, beyond +-1e6", stderr)
        scene["objects"][0]["max"] = [1e5, 1e5, 30]
        scene["objects"][0]["albedo"] = [0.5, 0.5, 0.5]
        path = self.write("scene_big_box.json", json.dumps(scene))
        proc = subprocess.run([CLI, "radiosity", "--scene", path, "--output",
                               os.path.join(self.dir, "scene_huge_out")],
                              capture_output=True, timeout=TIME_LIMIT)
        stderr = proc.stderr.decode("utf-8", "replace")
        self.assertGreater(proc.returncode, 0, stderr)
        self.assertIn("'room': the box would have about 5.55911e+08 patches at cell_size 6 mm",
                      stderr)

    def test_scene_deep(self):
        path = self.write("scene_deep.json", deep_json(100000, "objects"))
        out = os.path.join(self.dir, "scene_out")
        proc = subprocess.run([CLI, "radiosity", "--scene", path, "--output", out],
                              capture_output=True, timeout=TIME_LIMIT)
        stderr = proc.stderr.decode("utf-8", "replace")
        self.assertGreater(proc.returncode, 0, stderr)
        self.assertIn(path, stderr)
        self.assertIn("nested deeper than 64", stderr)


if __name__ == "__main__":
    unittest.main()
