#!/usr/bin/env python3
"""Tests of translucency.vtkTetGenReader, the reader of TetGen .node/.ele/.face files.

How to run (from a build tree):

    PYTHONPATH=<build>/lib/python3/dist-packages /usr/bin/python3 TestTetGenReader.py

1. Every test writes small TetGen files into a fresh temporary directory: a
   2 x 3 x 0.5 box split into 6 tetrahedra (1-based ids, comments, node
   attributes, boundary markers, region attributes, a .face file) or into 5
   tetrahedra (0-based ids, no optional columns).
2. The good files check counts, coordinates, connectivity, the arrays, and,
   independently of the reader, that the tetrahedra fill the box (summed
   volume) and the faces cover its surface (summed area).
3. Each bad file must raise a reader error (caught by an ErrorEvent observer)
   naming the file and the line or value at fault, and leave the output empty.

Exits non-zero on failure (unittest).
"""

import itertools
import os
import re
import sys
import tempfile
import unittest

import translucency
from vtkmodules.vtkCommonCore import vtkObject

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from vtk_chain import Messages  # noqa: E402

VTK_TETRA = 10

# The box [1, 3] x [-2, 1] x [0.5, 1]: corner k has coordinate bit a of k set
# when it lies on the upper side along axis a.
ORIGIN = (1.0, -2.0, 0.5)
EDGES = (2.0, 3.0, 0.5)
BOX_VOLUME = EDGES[0] * EDGES[1] * EDGES[2]
BOX_AREA = 2.0 * (EDGES[0] * EDGES[1] + EDGES[0] * EDGES[2] + EDGES[1] * EDGES[2])


def corner(k):
    return tuple(ORIGIN[a] + EDGES[a] * ((k >> a) & 1) for a in range(3))


CORNERS = [corner(k) for k in range(8)]


def sub(p, q):
    return tuple(a - b for a, b in zip(p, q))


def cross(u, v):
    return (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])


def dot(u, v):
    return sum(a * b for a, b in zip(u, v))


def signed_volume(p0, p1, p2, p3):
    """Volume of a tetrahedron, positive when p0 p1 p2 turn counterclockwise seen from p3."""
    return dot(cross(sub(p1, p0), sub(p2, p0)), sub(p3, p0)) / 6.0


def triangle_area(p0, p1, p2):
    n = cross(sub(p1, p0), sub(p2, p0))
    return 0.5 * dot(n, n) ** 0.5


def oriented(tet):
    """The tetrahedron (corner indices) with a positive volume."""
    a, b, c, d = tet
    if signed_volume(*(CORNERS[i] for i in tet)) < 0:
        return (a, b, d, c)
    return tuple(tet)


# Six tetrahedra around the diagonal from corner 0 to corner 7 (Kuhn split).
SIX_TETS = [oriented((0, 1 << p[0], (1 << p[0]) | (1 << p[1]), 7))
            for p in itertools.permutations(range(3))]
# Five tetrahedra: four corner tetrahedra and a central one.
FIVE_TETS = [oriented(t) for t in
             ((0, 1, 2, 4), (3, 1, 2, 7), (5, 1, 4, 7), (6, 2, 4, 7), (1, 2, 4, 7))]
SIX_REGIONS = [1.0, 1.0, 1.0, 2.0, 2.0, 7.5]


def boundary_faces(tets):
    """Triangles (sorted corner indices) that belong to exactly one tetrahedron."""
    count = {}
    for tet in tets:
        for face in itertools.combinations(sorted(tet), 3):
            count[face] = count.get(face, 0) + 1
    return sorted(face for face, n in count.items() if n == 1)


def face_marker(face):
    """1 + 2 * axis + side of the box side the triangle lies on."""
    for axis in range(3):
        bits = {(k >> axis) & 1 for k in face}
        if len(bits) == 1:
            return 1 + 2 * axis + bits.pop()
    raise AssertionError("not a boundary face: %r" % (face,))


def node_attributes(k):
    x, y, z = CORNERS[k]
    return (x + y, 10.0 * z)


def cube_node_lines():
    """The .node file of the six-tetrahedra box, 1-based, every optional column."""
    lines = ["# A 2 x 3 x 0.5 box: 8 corners",
             "# <#points> <dimension> <#attributes> <#boundary markers>",
             "8 3 2 1  # header",
             ""]
    for k in range(8):
        x, y, z = CORNERS[k]
        a0, a1 = node_attributes(k)
        values = ["%d" % (k + 1), repr(x), repr(y), repr(z), repr(a0), repr(a1), "%d" % (100 + k)]
        if k == 2:
            lines.append("\t".join(values))  # tabs
        elif k == 5:
            lines.append(", ".join(values) + "   # commas and a comment")
        else:
            lines.append("  " + " ".join(values))
    lines.append("# end of file")
    return lines


def cube_ele_lines():
    lines = ["# six tetrahedra around the diagonal from corner 1 to corner 8",
             "6 4 1"]
    for i, (tet, region) in enumerate(zip(SIX_TETS, SIX_REGIONS)):
        lines.append("%d  %s  %r  # tet" % (i + 1, " ".join(str(k + 1) for k in tet), region))
    return lines


def cube_face_lines():
    faces = boundary_faces(SIX_TETS)
    lines = ["%d 1 # faces, markers" % len(faces)]
    for i, face in enumerate(faces):
        lines.append("%d %s %d" % (i + 1, " ".join(str(k + 1) for k in face), face_marker(face)))
    return lines


def five_node_lines():
    """The .node file of the five-tetrahedra box, 0-based, no optional columns."""
    return ["8 3 0 0"] + ["%d %r %r %r" % ((k,) + CORNERS[k]) for k in range(8)]


def five_ele_lines():
    return ["5 4 0"] + ["%d %s" % (i, " ".join(map(str, tet))) for i, tet in enumerate(FIVE_TETS)]


class TetGenReaderTest(unittest.TestCase):

    def setUp(self):
        self._tmp = tempfile.TemporaryDirectory(prefix="tetgen-reader-")
        self.dir = self._tmp.name
        self.reader = translucency.vtkTetGenReader()
        self.messages = Messages(self.reader)

    def tearDown(self):
        self._tmp.cleanup()

    # -- helpers ---------------------------------------------------------

    def path(self, name):
        return os.path.join(self.dir, name)

    def write(self, name, lines):
        with open(self.path(name), "w") as f:
            f.write("\n".join(lines) + "\n")
        return self.path(name)

    def write_cube(self, base="cube", node=None, ele=None, face=None):
        self.write(base + ".node", cube_node_lines() if node is None else node)
        self.write(base + ".ele", cube_ele_lines() if ele is None else ele)
        if face is not False:
            self.write(base + ".face", cube_face_lines() if face is None else face)
        return self.path(base)

    def read(self, file_name):
        self.messages.clear()
        self.reader.SetFileName(file_name)
        self.reader.Modified()  # the files may have changed under the same name
        self.reader.Update()
        return self.reader.GetOutput()

    def read_ok(self, file_name):
        output = self.read(file_name)
        self.assertEqual(self.messages.errors, [])
        return output

    def assert_error(self, file_name, *patterns):
        """Reading fails with one reader error matching every regular expression."""
        output = self.read(file_name)
        self.assertEqual(len(self.messages.errors), 1, self.messages.errors)
        message = self.messages.errors[0]
        for pattern in patterns:
            self.assertRegex(message, pattern)
        self.assertEqual(output.GetNumberOfPoints(), 0, message)
        self.assertEqual(output.GetNumberOfCells(), 0, message)
        self.assertEqual(output.GetPointData().GetNumberOfArrays(), 0)
        self.assertEqual(output.GetCellData().GetNumberOfArrays(), 0)
        self.assertEqual(output.GetFieldData().GetNumberOfArrays(), 0)
        return message

    def tets(self, output):
        ids = []
        for c in range(output.GetNumberOfCells()):
            cell_ids = output.GetCell(c).GetPointIds()
            ids.append(tuple(cell_ids.GetId(i) for i in range(cell_ids.GetNumberOfIds())))
        return ids

    def total_volume(self, output):
        volume = 0.0
        for tet in self.tets(output):
            v = signed_volume(*(output.GetPoint(i) for i in tet))
            self.assertGreater(v, 0.0, "tetrahedron %r is inverted or flat" % (tet,))
            volume += v
        return volume

    # -- good files --------------------------------------------------------

    def test_cube_one_based(self):
        output = self.read_ok(self.write_cube() + ".node")
        self.assertEqual(self.messages.warnings, [])
        self.assertEqual(output.GetNumberOfPoints(), 8)
        self.assertEqual(output.GetNumberOfCells(), 6)
        self.assertEqual(output.GetPoints().GetDataType(), 11)  # VTK_DOUBLE
        for c in range(6):
            self.assertEqual(output.GetCellType(c), VTK_TETRA)
        for k in range(8):
            for got, want in zip(output.GetPoint(k), CORNERS[k]):
                self.assertEqual(got, want)
        # TetGen id i + 1 is output point i; the node order is kept.
        self.assertEqual(self.tets(output), SIX_TETS)
        self.assertAlmostEqual(self.total_volume(output), BOX_VOLUME, places=12)

        pd = output.GetPointData()
        self.assertEqual(pd.GetNumberOfArrays(), 3)
        for a in range(2):
            array = pd.GetArray("NodeAttribute%d" % a)
            self.assertIsNotNone(array)
            self.assertEqual(array.GetClassName(), "vtkDoubleArray")
            self.assertEqual([array.GetValue(k) for k in range(8)],
                             [node_attributes(k)[a] for k in range(8)])
        markers = pd.GetArray("BoundaryMarker")
        self.assertEqual(markers.GetClassName(), "vtkIntArray")
        self.assertEqual([markers.GetValue(k) for k in range(8)], [100 + k for k in range(8)])

        region = output.GetCellData().GetArray("RegionAttribute")
        self.assertIsNotNone(region)
        self.assertEqual(region.GetClassName(), "vtkDoubleArray")
        self.assertEqual(region.GetNumberOfComponents(), 1)
        self.assertEqual([region.GetValue(c) for c in range(6)], SIX_REGIONS)
        self.assertEqual(output.GetCellData().GetNumberOfArrays(), 1)

    def test_cube_faces(self):
        output = self.read_ok(self.write_cube() + ".node")
        fd = output.GetFieldData()
        faces = fd.GetArray("TetGenFaces")
        markers = fd.GetArray("TetGenFaceMarkers")
        self.assertEqual(faces.GetClassName(), "vtkIntArray")
        self.assertEqual(faces.GetNumberOfComponents(), 3)
        self.assertEqual(markers.GetClassName(), "vtkIntArray")
        expected = boundary_faces(SIX_TETS)
        self.assertEqual(len(expected), 12)
        self.assertEqual(faces.GetNumberOfTuples(), 12)
        self.assertEqual(markers.GetNumberOfTuples(), 12)
        got = [tuple(int(v) for v in faces.GetTuple3(i)) for i in range(12)]
        self.assertEqual(got, expected)  # 0-based output point ids
        self.assertEqual([markers.GetValue(i) for i in range(12)],
                         [face_marker(f) for f in expected])
        # Independent check: the faces cover the surface of the box once, and
        # each is a face of exactly one output tetrahedron.
        area = sum(triangle_area(*(output.GetPoint(i) for i in f)) for f in got)
        self.assertAlmostEqual(area, BOX_AREA, places=12)
        self.assertEqual(boundary_faces(self.tets(output)), sorted(tuple(sorted(f)) for f in got))
        # Markers 1..6: each side of the box is two triangles.
        self.assertEqual(sorted(markers.GetValue(i) for i in range(12)),
                         [m for m in range(1, 7) for _ in range(2)])

    def test_read_faces_off_and_missing_face_file(self):
        base = self.write_cube()
        self.reader.ReadFacesOff()
        output = self.read_ok(base + ".node")
        self.assertEqual(output.GetNumberOfCells(), 6)
        self.assertEqual(output.GetFieldData().GetNumberOfArrays(), 0)
        self.reader.ReadFacesOn()
        os.remove(base + ".face")
        output = self.read_ok(base + ".node")  # a missing .face is not an error
        self.assertEqual(output.GetNumberOfCells(), 6)
        self.assertEqual(output.GetFieldData().GetNumberOfArrays(), 0)

    def test_default_and_file_name_forms(self):
        self.assertTrue(self.reader.GetReadFaces())
        self.assertIsNone(self.reader.GetFileName())
        base = self.write_cube()
        for name in (base, base + ".node", base + ".ele", base + ".face"):
            output = self.read_ok(name)
            self.assertEqual(output.GetNumberOfPoints(), 8, name)
            self.assertEqual(output.GetNumberOfCells(), 6, name)
            self.assertEqual(self.tets(output), SIX_TETS, name)

    def test_five_tets_zero_based(self):
        self.write("five.node", five_node_lines())
        self.write("five.ele", five_ele_lines())
        output = self.read_ok(self.path("five.ele"))
        self.assertEqual(output.GetNumberOfPoints(), 8)
        self.assertEqual(output.GetNumberOfCells(), 5)
        self.assertEqual(self.tets(output), FIVE_TETS)  # 0-based ids are used as they are
        self.assertAlmostEqual(self.total_volume(output), BOX_VOLUME, places=12)
        # The central tetrahedron is a third of the box.
        central = self.tets(output)[4]
        self.assertAlmostEqual(signed_volume(*(output.GetPoint(i) for i in central)),
                               BOX_VOLUME / 3.0, places=12)
        self.assertEqual(output.GetPointData().GetNumberOfArrays(), 0)
        self.assertEqual(output.GetCellData().GetNumberOfArrays(), 0)
        self.assertEqual(output.GetFieldData().GetNumberOfArrays(), 0)

    def test_quadratic_tetrahedra(self):
        # One 10-node tetrahedron: 4 corners and the 6 edge midpoints.
        corners = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]
        mids = [tuple((a + b) / 2 for a, b in zip(corners[i], corners[j]))
                for i, j in ((0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3))]
        points = corners + mids
        self.write("quad.node", ["10 3"] + ["%d %r %r %r" % ((i + 1,) + p)
                                            for i, p in enumerate(points)])
        self.write("quad.ele", ["1 10 0", "1 " + " ".join(str(i + 1) for i in range(10))])
        output = self.read_ok(self.path("quad"))
        self.assertEqual(output.GetNumberOfPoints(), 10)
        self.assertEqual(self.tets(output), [(0, 1, 2, 3)])
        self.assertAlmostEqual(self.total_volume(output), 1.0 / 6.0, places=14)
        self.assertEqual(len(self.messages.warnings), 1)
        self.assertRegex(self.messages.warnings[0], r"quad\.ele'.*10-node")

    def test_can_read_file(self):
        base = self.write_cube()
        for name in (base, base + ".node", base + ".ele"):
            self.assertEqual(self.reader.CanReadFile(name), 1, name)
        self.write("noele.node", cube_node_lines())
        self.assertEqual(self.reader.CanReadFile(self.path("noele.node")), 0)
        self.assertEqual(self.reader.CanReadFile(self.path("nothing.node")), 0)
        self.write("flat.node", ["3 2 0 0", "1 0 0", "2 1 0", "3 0 1"])
        self.write("flat.ele", ["0 4 0"])
        self.assertEqual(self.reader.CanReadFile(self.path("flat.node")), 0)
        self.write("text.node", ["hello world"])
        self.write("text.ele", ["6 4 1"])
        self.assertEqual(self.reader.CanReadFile(self.path("text.ele")), 0)
        self.assertEqual(self.messages.errors, [])  # CanReadFile never reports errors

    def test_reuse_after_error(self):
        base = self.write_cube()
        self.assertEqual(self.read_ok(base).GetNumberOfCells(), 6)
        self.assert_error(self.path("missing.node"), r"missing\.node' does not exist")
        self.assertEqual(self.read_ok(base).GetNumberOfCells(), 6)

    # -- bad files ---------------------------------------------------------

    def test_no_file_name(self):
        self.assert_error(None, r"No FileName")

    def test_missing_node_file(self):
        self.assert_error(self.path("none.node"),
                          re.escape(self.path("none.node")) + "' does not exist")

    def test_missing_ele_file(self):
        self.write("lonely.node", cube_node_lines())
        self.assert_error(self.path("lonely.node"),
                          re.escape(self.path("lonely.ele")) + "' does not exist")

    def test_node_file_is_a_directory(self):
        os.mkdir(self.path("dir.node"))
        self.write("dir.ele", cube_ele_lines())
        self.assert_error(self.path("dir.ele"), r"dir\.node' is not a regular file")

    def test_empty_node_file(self):
        base = self.write_cube(node=["# nothing but a comment", ""])
        self.assert_error(base, r"cube\.node' is empty or holds only comments",
                          r"<#points> <dimension")

    def test_truncated_node_file(self):
        lines = cube_node_lines()[:-3]  # drop two nodes and the final comment
        base = self.write_cube(node=lines)
        self.assert_error(base, r"cube\.node' is truncated: node 7 of 8 \(as declared on line 3\)"
                          r" was expected on line %d" % (len(lines) + 1))

    def test_truncated_ele_file(self):
        lines = cube_ele_lines()[:-1]
        base = self.write_cube(ele=lines)
        self.assert_error(base, r"cube\.ele' is truncated: tetrahedron 6 of 6 .* "
                          r"expected on line %d" % (len(lines) + 1))

    def test_huge_count_in_short_file(self):
        lines = cube_node_lines()
        lines[2] = "1000000000000 3 2 1"
        base = self.write_cube(node=lines)
        self.assert_error(base, r"cube\.node' is truncated: node 9 of 1000000000000")

    def test_malformed_coordinate(self):
        lines = cube_node_lines()
        lines[6] = "3 1.0 1.0x 0.5 0 0 102"
        base = self.write_cube(node=lines)
        self.assert_error(base, r"cube\.node', line 7: malformed number '1\.0x'",
                          r"y coordinate of node 3")

    def test_malformed_node_index(self):
        lines = cube_ele_lines()
        lines[3] = "2 1 3a 4 8 1.0"
        base = self.write_cube(ele=lines)
        self.assert_error(base, r"cube\.ele', line 4: malformed number '3a'",
                          r"node 2 of element 2")

    def test_malformed_header(self):
        lines = cube_ele_lines()
        lines[1] = "six 4 1"
        base = self.write_cube(ele=lines)
        self.assert_error(base, r"cube\.ele', line 2: malformed number 'six'",
                          r"number of tetrahedra")

    def test_element_refers_to_missing_node(self):
        lines = cube_ele_lines()
        tet = SIX_TETS[3]
        lines[5] = "4 %d %d %d 99 2.0" % (tet[0] + 1, tet[1] + 1, tet[2] + 1)
        base = self.write_cube(ele=lines)
        self.assert_error(base, r"cube\.ele', line 6: element 4 refers to node 99, "
                          r"which does not exist", r"cube\.node' has nodes 1 to 8")

    def test_one_based_element_refers_to_node_zero(self):
        lines = cube_ele_lines()
        lines[2] = "1 0 2 4 8 1.0"
        base = self.write_cube(ele=lines)
        self.assert_error(base, r"cube\.ele', line 3: element 1 refers to node 0, "
                          r"which does not exist")

    def test_zero_based_element_refers_to_node_eight(self):
        self.write("five.node", five_node_lines())
        lines = five_ele_lines()
        lines[5] = "4 1 2 4 8"
        self.write("five.ele", lines)
        self.assert_error(self.path("five"), r"five\.ele', line 6: element 4 refers to node 8, "
                          r"which does not exist", r"has nodes 0 to 7")

    def test_face_refers_to_missing_node(self):
        lines = cube_face_lines()
        lines[4] = "4 1 2 42 1"
        base = self.write_cube(face=lines)
        self.assert_error(base, r"cube\.face', line 5: face 4 refers to node 42, "
                          r"which does not exist")

    def test_dimension_two(self):
        lines = cube_node_lines()
        lines[2] = "8 2 2 1"
        base = self.write_cube(node=lines)
        self.assert_error(base, r"cube\.node', line 3: the dimension in the header is 2")

    def test_nodes_per_tetrahedron(self):
        lines = cube_ele_lines()
        lines[1] = "6 5 1"
        base = self.write_cube(ele=lines)
        self.assert_error(base, r"cube\.ele', line 2: the number of nodes per tetrahedron "
                          r"in the header is 5")

    def test_negative_count(self):
        lines = cube_node_lines()
        lines[2] = "-8 3 2 1"
        base = self.write_cube(node=lines)
        self.assert_error(base, r"cube\.node', line 3: the number of points in the header "
                          r"is negative \(-8\)")

    def test_short_node_line(self):
        lines = cube_node_lines()
        lines[8] = "5 1.0 -2.0 1.0 -1.0 10.0"  # the marker is missing
        base = self.write_cube(node=lines)
        self.assert_error(base, r"cube\.node', line 9: 6 values were found but 7 are expected",
                          r"boundary marker")

    def test_non_consecutive_node_ids(self):
        lines = cube_node_lines()
        lines[7] = lines[7].replace("4", "40", 1)
        base = self.write_cube(node=lines)
        self.assert_error(base, r"cube\.node', line 8: node id 40 found where 4 was expected")

    def test_first_node_id(self):
        lines = five_node_lines()
        lines[1] = lines[1].replace("0", "5", 1)
        self.write("five.node", lines)
        self.write("five.ele", five_ele_lines())
        self.assert_error(self.path("five"), r"five\.node', line 2: the first node id is 5")

    def test_non_finite_coordinate(self):
        lines = five_node_lines()
        lines[3] = "2 nan 3.0 0.5"
        self.write("five.node", lines)
        self.write("five.ele", five_ele_lines())
        self.assert_error(self.path("five"), r"five\.node', line 4: the x coordinate of node 2 "
                          r"is 'nan', which is not a finite number")

    def test_bad_face_marker_count(self):
        lines = cube_face_lines()
        lines[0] = "12 3"
        base = self.write_cube(face=lines)
        self.assert_error(base, r"cube\.face', line 1: the number of boundary markers in the "
                          r"header must be 0 or 1, not 3")

    def test_binary_garbage(self):
        with open(self.path("junk.node"), "wb") as f:
            f.write(bytes(range(256)) * 64)
        self.write("junk.ele", cube_ele_lines())
        self.assert_error(self.path("junk"), r"junk\.node', line 1: malformed number")


if __name__ == "__main__":
    # Messages go to the observers; nothing should reach the output window.
    vtkObject.GlobalWarningDisplayOn()
    sys.exit(0 if unittest.main(exit=False, verbosity=2).result.wasSuccessful() else 1)
