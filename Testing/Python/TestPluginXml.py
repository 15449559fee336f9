#!/usr/bin/env python3
"""The ParaView panels as the plugin XML describes them (issue 20: 21 properties
had no tooltip; Assign Scattering Coefficients showed explicit coefficients
that a preset ignores).

How to run (no ParaView needed; ctest does this):

    TRANSLUCENCY_SOURCE_DIR=<source> /usr/bin/python3 TestPluginXml.py

1. Every proxy of Plugin/*.xml and every one of its properties (inputs and
   information-only ones included) has a non-empty <Documentation>, which
   ParaView shows as the tooltip and in the "?" help.
2. Every PropertyWidgetDecorator names a property of its own proxy, and every
   RequiredProperties entry too.
3. Assign Scattering Coefficients shows only what applies: the decorators,
   evaluated here as ParaView's GenericDecorator (value / values / inverse)
   and CompositeDecorator (nested and / or) do, give for each material mode
   and Material Name (a preset or empty) exactly the properties the filter
   reads (vtkAssignScatteringCoefficients::ComputeMaterials): Material Name in
   the Uniform mode; the explicit mu_a and sigma_s' in the Uniform mode with
   an empty name; the refractive index there and in the Volume mode.
4. Solve Diffusion's and Translucent Radiosity's Linear Solver are drop-downs
   fed by an information property of the filter (GetAvailableLinearSolvers),
   defaulting to "default" and "cg-jacobi".
5. The "?" help: the plugin is built with XML_DOCUMENTATION, so the build
   has a Qt help collection (Plugin/paraview_help/Translucency.qch, an SQLite
   file the plugin embeds and ParaView registers at load) with one page per
   proxy, and each page holds every property's label and documentation
   (needs TRANSLUCENCY_BINARY_DIR; skipped without it).

Exits non-zero on failure (unittest).
"""

import glob
import html
import os
import re
import sqlite3
import unittest
import zlib
import xml.etree.ElementTree as ET

SOURCE_DIR = os.environ.get("TRANSLUCENCY_SOURCE_DIR") or os.path.abspath(
    os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
PLUGIN_DIR = os.path.join(SOURCE_DIR, "Plugin")


def proxies():
    """(file, proxy element) of every proxy of the plugin."""
    files = sorted(glob.glob(os.path.join(PLUGIN_DIR, "*.xml")))
    assert files, "no XML in " + PLUGIN_DIR
    for path in files:
        root = ET.parse(path).getroot()
        for group in root.findall("ProxyGroup"):
            for proxy in group:
                if proxy.tag.endswith("Proxy"):
                    yield os.path.basename(path), proxy


def properties(proxy):
    return [p for p in proxy if p.tag.endswith("Property")]


def documentation(element):
    doc = element.find("Documentation")
    return " ".join((doc.text or "").split()) if doc is not None else ""


def decorators(element):
    hints = element.find("Hints")
    return [] if hints is None else hints.findall("PropertyWidgetDecorator")


def visible(decorator, values):
    """Whether `decorator` shows its widget for the property `values` (a dict
    name -> value as a string), as ParaView's decorators decide it."""
    kind = decorator.get("type")
    if kind == "GenericDecorator":
        assert decorator.get("mode") == "visibility", decorator.attrib
        name = decorator.get("property")
        if name not in values:
            raise KeyError("the decorator names the unknown property '%s'" % name)
        wanted = ([decorator.get("value")] if decorator.get("value") is not None
                  else decorator.get("values").split(" "))
        match = values[name] in wanted
        return not match if decorator.get("inverse") == "1" else match
    if kind == "CompositeDecorator":
        expressions = decorator.findall("Expression")
        assert len(expressions) == 1, "a CompositeDecorator holds one Expression"
        return evaluate(expressions[0], values)
    if kind == "TranslucencyLinearSolverDecorator":
        return True  # the plugin's own: it filters the drop-down, never hides it
    raise AssertionError("unexpected decorator type %s" % kind)


def evaluate(expression, values):
    terms = []
    for child in expression:
        if child.tag == "Expression":
            terms.append(evaluate(child, values))
        elif child.tag == "PropertyWidgetDecorator":
            terms.append(visible(child, values))
    kind = expression.get("type")
    assert kind in ("and", "or"), kind
    return all(terms) if kind == "and" else any(terms)


def shown(prop, values):
    return all(visible(d, values) for d in decorators(prop))


def referenced_properties(element):
    """Property names an element's decorators and required properties refer to."""
    for node in element.iter():
        if node.tag == "PropertyWidgetDecorator":
            for attribute in ("property", "solver_property", "table_property"):
                if node.get(attribute):
                    yield node.get(attribute)
        if node.tag == "RequiredProperties":
            for required in node.findall("Property"):
                yield required.get("name")


class PluginXmlTest(unittest.TestCase):

    def test_every_proxy_and_property_is_documented(self):
        undocumented = []
        count = 0
        for path, proxy in proxies():
            if not documentation(proxy):
                undocumented.append("%s: proxy %s" % (path, proxy.get("name")))
            for prop in properties(proxy):
                count += 1
                if not documentation(prop):
                    undocumented.append("%s: %s %s" % (path, proxy.get("name"), prop.get("name")))
        self.assertGreater(count, 100)
        self.assertEqual(undocumented, [], "properties without <Documentation> (tooltip)")

    def test_references_name_properties_of_the_same_proxy(self):
        for path, proxy in proxies():
            names = {p.get("name") for p in properties(proxy)}
            for name in referenced_properties(proxy):
                with self.subTest(file=path, proxy=proxy.get("name")):
                    self.assertIn(name, names)

    def test_assign_shows_only_what_applies(self):
        proxy = next(p for _, p in proxies() if p.get("name") == "AssignScatteringCoefficients")
        by_name = {p.get("name"): p for p in properties(proxy)}
        defaults = {name: p.get("default_values", "") for name, p in by_name.items()}
        modes = {e.get("value"): e.get("text")
                 for e in by_name["MaterialMode"].find("EnumerationDomain")}
        self.assertEqual(modes["0"], "Uniform")
        self.assertEqual(modes["5"], "Volume")
        for mode in modes:
            for material in ("", "marble", "skin1"):
                values = dict(defaults, MaterialMode=mode, MaterialName=material)
                uniform_explicit = mode == "0" and material == ""
                expected = {
                    "MaterialName": mode == "0",
                    "AbsorptionCoefficient": uniform_explicit,
                    "ReducedScatteringCoefficient": uniform_explicit,
                    "RefractiveIndex": uniform_explicit or mode == "5",
                    "MaterialIdArrayName": mode == "1",
                    "InclusionRadius": mode == "2",
                    "Layers": mode == "3",
                    "VeinMaterial": mode == "4",
                    "VolumeAbsorptionArrayName": mode == "5",
                }
                for name, wanted in expected.items():
                    with self.subTest(mode=modes[mode], material=material, property=name):
                        self.assertEqual(shown(by_name[name], values), wanted)

    def test_linear_solver_is_a_drop_down_of_the_build(self):
        for proxy_name, default in (("SolveDiffusion", "default"),
                                    ("TranslucentRadiosity", "cg-jacobi")):
            with self.subTest(proxy=proxy_name):
                proxy = next(p for _, p in proxies() if p.get("name") == proxy_name)
                by_name = {p.get("name"): p for p in properties(proxy)}
                linear = by_name["LinearSolver"]
                self.assertEqual(linear.get("default_values"), default)
                domain = linear.find("StringListDomain")
                self.assertIsNotNone(domain, "Linear Solver is not a drop-down")
                self.assertEqual(domain.findall("String"), [], "the list comes from the filter")
                required = domain.find("RequiredProperties").find("Property")
                self.assertEqual(required.get("function"), "ArrayList")
                info = by_name[required.get("name")]
                self.assertEqual(info.get("information_only"), "1")
                self.assertEqual(info.get("command"), "GetAvailableLinearSolvers")
                self.assertIsNotNone(info.find("StringArrayHelper"))

    def test_linear_solver_follows_the_solver(self):
        # Issue 33: Solve Diffusion's Linear Solver has the plugin's decorator,
        # fed by the filter's table of accepted linear solvers per solver.
        proxy = next(p for _, p in proxies() if p.get("name") == "SolveDiffusion")
        by_name = {p.get("name"): p for p in properties(proxy)}
        kinds = [d.get("type") for d in decorators(by_name["LinearSolver"])]
        self.assertIn("TranslucencyLinearSolverDecorator", kinds)
        decorator = next(d for d in decorators(by_name["LinearSolver"])
                         if d.get("type") == "TranslucencyLinearSolverDecorator")
        self.assertEqual(by_name[decorator.get("solver_property")].find("EnumerationDomain")
                         is not None, True)
        table = by_name[decorator.get("table_property")]
        self.assertEqual(table.get("information_only"), "1")
        self.assertEqual(table.get("command"), "GetLinearSolverTable")
        self.assertIsNotNone(table.find("StringArrayHelper"))

    def test_tables_have_a_label_and_column_headers(self):
        # Every repeatable property with several numbers per row (a table in the
        # panel: Point Sources, Pencil Beams, Detectors, light lists...) has a
        # label and one column header per number (ShowComponentLabels).
        tables = 0
        for name, proxy in proxies():
            for prop in properties(proxy):
                per_row = int(prop.get("number_of_elements_per_command", "1"))
                if prop.get("repeat_command") != "1" or prop.get("information_only") == "1":
                    continue
                if prop.get("name") not in ("PointSources", "PencilBeams", "Detectors",
                                            "TimeSnapshots"):
                    continue
                tables += 1
                where = "%s %s" % (name, prop.get("name"))
                self.assertTrue(prop.get("label"), where + ": no label")
                hints = prop.find("Hints")
                self.assertIsNotNone(hints, where + ": no hints")
                self.assertIsNotNone(hints.find("ShowLabel"), where + ": label not shown")
                labels = hints.find("ShowComponentLabels")
                self.assertIsNotNone(labels, where + ": no column headers")
                components = sorted(int(c.get("component")) for c in labels)
                self.assertEqual(components, list(range(per_row)), where)
                self.assertTrue(all(c.get("label") for c in labels), where)
        self.assertEqual(tables, 4)

    def test_radiance_readout_defaults_to_energy_conserving(self):
        prop = next(p for name, proxy in proxies() if proxy.get("name") == "OutgoingRadiance"
                    for p in properties(proxy) if p.get("name") == "RadianceReadout")
        entries = {e.get("value"): e.get("text")
                   for e in prop.find("EnumerationDomain").findall("Entry")}
        # The values are vtkOutgoingRadiance::ENERGY_CONSERVING (0) and PAPER (1).
        self.assertEqual(entries, {"0": "energy-conserving", "1": "paper"})
        self.assertEqual(entries[prop.get("default_values")], "energy-conserving")

    def test_help_pages_hold_every_property(self):
        binary = os.environ.get("TRANSLUCENCY_BINARY_DIR")
        if not binary:
            self.skipTest("TRANSLUCENCY_BINARY_DIR not set")
        qch = os.path.join(binary, "Plugin", "paraview_help", "Translucency.qch")
        self.assertTrue(os.path.isfile(qch), "no help collection: " + qch)
        db = sqlite3.connect(qch)
        pages = {}
        for file_id, name in db.execute("SELECT FileId, Name FROM FileNameTable"):
            data = db.execute("SELECT Data FROM FileDataTable WHERE Id = ?",
                              (file_id,)).fetchone()
            if name.endswith(".html") and data:
                # qCompress: a 4-byte big-endian length, then zlib.
                pages[name] = zlib.decompress(data[0][4:]).decode("utf-8")
        db.close()

        def words(text):
            """The text of an HTML page or of a Documentation element."""
            return " ".join(html.unescape(re.sub(r"<[^>]+>", " ", text)).split())

        count = 0
        for path, proxy in proxies():
            group = "sources" if proxy.tag == "SourceProxy" and proxy.find(
                "InputProperty") is None else "filters"
            name = "%s.%s.html" % (group, proxy.get("name"))
            self.assertIn(name, pages, "no help page for %s (%s)" % (proxy.get("name"), path))
            page = words(pages[name])
            for prop in proxy:
                doc = prop.find("Documentation")
                if prop.get("name") is None or doc is None or prop.get("panel_visibility") == \
                        "never" or prop.get("information_only") == "1":
                    continue
                self.assertIn(" ".join((doc.text or "").split())[:60], page,
                              "%s: the help of %s lacks its documentation"
                              % (name, prop.get("name")))
                count += 1
        self.assertGreater(count, 60)


if __name__ == "__main__":
    unittest.main(verbosity=2)
