// The ParaView plugin's lists of names against the core's, so that a name is
// written once: the Solver drop-down of Plugin/SolveDiffusion.xml must list
// GetDiffusionSolverNames() in order with values 0..n-1 (vtkSolveDiffusion
// passes the value through as an index into the names), and the LinearSolver
// documentation of that proxy must name every solver of GetLinearSolverNames().
// The XML is read as text (the core is VTK-free): a few start tags, their
// attributes and the five predefined entities are all this needs.

#include "CollimatedModels.h"
#include "DiffusionSolverFactory.h"
#include "Error.h"
#include "LinearSolver.h"

#include <gtest/gtest.h>

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace
{

const std::string SolveDiffusionXml = std::string(TRANSLUCENCY_PLUGIN_DIR) + "/SolveDiffusion.xml";
const std::string SurfaceIrradianceXml =
  std::string(TRANSLUCENCY_PLUGIN_DIR) + "/SurfaceIrradiance.xml";

std::string ReadText(const std::string& fileName)
{
  std::ifstream in(fileName);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string DecodeEntities(std::string text)
{
  const std::pair<const char*, const char*> entities[] = { { "&lt;", "<" }, { "&gt;", ">" },
    { "&quot;", "\"" }, { "&apos;", "'" }, { "&amp;", "&" } };
  for (const auto& [entity, character] : entities)
  {
    for (std::size_t at = text.find(entity); at != std::string::npos;
         at = text.find(entity, at + 1))
    {
      text.replace(at, std::string(entity).size(), character);
    }
  }
  return text;
}

/// The attributes of the start tag that begins at `begin` (at its '<').
std::map<std::string, std::string> Attributes(const std::string& xml, std::size_t begin)
{
  const std::size_t end = xml.find('>', begin);
  const std::string tag = xml.substr(begin, end - begin);
  static const std::regex attribute(R"(([A-Za-z_][-\w.:]*)\s*=\s*"([^"]*)\")");
  std::map<std::string, std::string> result;
  for (std::sregex_iterator it(tag.begin(), tag.end(), attribute), last; it != last; ++it)
  {
    result[(*it)[1]] = DecodeEntities((*it)[2]);
  }
  return result;
}

/// Start offsets of the elements <tag ...> in xml (not <tagSuffix ...>).
std::vector<std::size_t> StartTags(const std::string& xml, const std::string& tag)
{
  std::vector<std::size_t> starts;
  const std::string open = "<" + tag;
  for (std::size_t at = xml.find(open); at != std::string::npos; at = xml.find(open, at + 1))
  {
    const char next = xml[at + open.size()];
    if (next == ' ' || next == '\n' || next == '\t' || next == '\r' || next == '>' ||
      next == '/')
    {
      starts.push_back(at);
    }
  }
  return starts;
}

/// The whole element <tag name="name" ...> ... </tag> (the tags in the
/// plugin XML do not nest in themselves); empty if there is none.
std::string Element(const std::string& xml, const std::string& tag, const std::string& name)
{
  for (const std::size_t start : StartTags(xml, tag))
  {
    if (Attributes(xml, start)["name"] == name)
    {
      const std::string close = "</" + tag + ">";
      const std::size_t end = xml.find(close, start);
      return end == std::string::npos ? std::string()
                                      : xml.substr(start, end + close.size() - start);
    }
  }
  return {};
}

/// The text between <tag ...> and </tag> of the first such element.
std::string Content(const std::string& xml, const std::string& tag)
{
  const std::vector<std::size_t> starts = StartTags(xml, tag);
  if (starts.empty())
  {
    return {};
  }
  const std::size_t begin = xml.find('>', starts.front()) + 1;
  const std::size_t end = xml.find("</" + tag + ">", begin);
  return end == std::string::npos ? std::string() : DecodeEntities(xml.substr(begin, end - begin));
}

struct Entry
{
  std::string Text;
  std::string Value;
  std::string Info;
};

/// The <Entry text=".." value=".."/> of the EnumerationDomain of `property`.
std::vector<Entry> EnumerationEntries(const std::string& property)
{
  std::vector<Entry> entries;
  const std::string domain = Element(property, "EnumerationDomain", "enum");
  for (const std::size_t start : StartTags(domain, "Entry"))
  {
    auto attributes = Attributes(domain, start);
    entries.push_back({ attributes["text"], attributes["value"], attributes["info"] });
  }
  return entries;
}

TEST(PluginEnumerations, SolveDiffusionSolverListsTheDiffusionSolverNames)
{
  const std::string xml = ReadText(SolveDiffusionXml);
  ASSERT_FALSE(xml.empty()) << "cannot read " << SolveDiffusionXml;
  const std::string proxy = Element(xml, "SourceProxy", "SolveDiffusion");
  ASSERT_FALSE(proxy.empty()) << "no SourceProxy SolveDiffusion in " << SolveDiffusionXml;
  const std::string property = Element(proxy, "IntVectorProperty", "Solver");
  ASSERT_FALSE(property.empty()) << "no IntVectorProperty Solver in " << SolveDiffusionXml;

  const std::vector<Entry> entries = EnumerationEntries(property);
  const std::vector<std::string> names = translucency::GetDiffusionSolverNames();
  ASSERT_EQ(entries.size(), names.size())
    << "the Solver EnumerationDomain of " << SolveDiffusionXml << " has " << entries.size()
    << " entries, translucency::GetDiffusionSolverNames() " << names.size()
    << " names: add or remove the solver on both sides";
  for (std::size_t k = 0; k < names.size(); ++k)
  {
    EXPECT_EQ(entries[k].Text, names[k])
      << "entry " << k << " of the Solver EnumerationDomain of " << SolveDiffusionXml
      << ": its text must be GetDiffusionSolverNames()[" << k << "]";
    EXPECT_EQ(entries[k].Value, std::to_string(k))
      << "entry " << k << " (" << entries[k].Text << ") of the Solver EnumerationDomain of "
      << SolveDiffusionXml << ": the values are 0..n-1 in the order of the names";
  }
}

TEST(PluginEnumerations, SolveDiffusionSolverEntriesShowTheRegistryHelp)
{
  // The drop-down's line under each solver (the Entry's info) is the
  // registry's one line of help, the same as `translucency help render`
  // prints: written once, in the registry.
  const std::string xml = ReadText(SolveDiffusionXml);
  const std::string property =
    Element(Element(xml, "SourceProxy", "SolveDiffusion"), "IntVectorProperty", "Solver");
  ASSERT_FALSE(property.empty()) << "no IntVectorProperty Solver in " << SolveDiffusionXml;
  const auto& registry = translucency::GetDiffusionSolverRegistry();
  for (const Entry& entry : EnumerationEntries(property))
  {
    const auto* registered = registry.Find(entry.Text);
    ASSERT_NE(registered, nullptr) << entry.Text;
    EXPECT_EQ(entry.Info, registered->Help)
      << "the info of the Solver entry '" << entry.Text << "' in " << SolveDiffusionXml
      << " must be the registry's help line (DiffusionSolverFactory.cxx)";
  }
}

/// The names a StringListDomain of `property` lists (<String value=".."/>),
/// the empty one (meaning "default") left out.
std::vector<std::string> StringListNames(const std::string& property)
{
  std::vector<std::string> names;
  const std::vector<std::size_t> domains = StartTags(property, "StringListDomain");
  if (!domains.empty())
  {
    const std::size_t end = property.find("</StringListDomain>", domains.front());
    const std::string domain = property.substr(domains.front(), end - domains.front());
    for (const std::size_t start : StartTags(domain, "String"))
    {
      const std::string value = Attributes(domain, start)["value"];
      if (!value.empty())
      {
        names.push_back(value);
      }
    }
  }
  return names;
}

TEST(PluginEnumerations, LinearSolverListsAreTheLinearSolverNames)
{
  // Every LinearSolver property of the plugin is a free string today (the
  // solvers of a build vary); should one get a list of names, it must be
  // GetLinearSolverNames() in order.
  const std::vector<std::string> names = translucency::GetLinearSolverNames();
  int properties = 0;
  for (const auto& file : std::filesystem::directory_iterator(TRANSLUCENCY_PLUGIN_DIR))
  {
    if (file.path().extension() != ".xml")
    {
      continue;
    }
    const std::string xml = ReadText(file.path().string());
    for (const char* type : { "StringVectorProperty", "IntVectorProperty" })
    {
      const std::string property = Element(xml, type, "LinearSolver");
      if (property.empty())
      {
        continue;
      }
      ++properties;
      std::vector<std::string> listed = StringListNames(property);
      for (const Entry& entry : EnumerationEntries(property))
      {
        listed.push_back(entry.Text);
        EXPECT_EQ(entry.Value, std::to_string(listed.size() - 1)) << file.path();
      }
      if (!listed.empty())
      {
        EXPECT_EQ(listed, names) << "the LinearSolver names of " << file.path()
                                 << " must be translucency::GetLinearSolverNames(), in order";
      }
    }
  }
  EXPECT_EQ(properties, 2) << "LinearSolver properties in " << TRANSLUCENCY_PLUGIN_DIR
                           << " (Solve Diffusion, Translucent Radiosity)";
}

TEST(PluginEnumerations, SolveDiffusionLinearSolverDocumentationNamesEveryLinearSolver)
{
  // The LinearSolver property of Solve Diffusion lists the names in its
  // documentation: it must name every solver the core has (the optional ones
  // as "when built").
  const std::string xml = ReadText(SolveDiffusionXml);
  ASSERT_FALSE(xml.empty()) << "cannot read " << SolveDiffusionXml;
  const std::string property =
    Element(Element(xml, "SourceProxy", "SolveDiffusion"), "StringVectorProperty", "LinearSolver");
  ASSERT_FALSE(property.empty()) << "no StringVectorProperty LinearSolver in " << SolveDiffusionXml;
  const std::string documentation = Content(property, "Documentation");
  for (const std::string& name : translucency::GetLinearSolverNames())
  {
    const std::regex word("(^|[^-\\w])" + name + "($|[^-\\w])");
    EXPECT_TRUE(std::regex_search(documentation, word))
      << "the LinearSolver documentation of " << SolveDiffusionXml
      << " does not name the linear solver '" << name << "' of GetLinearSolverNames()";
  }
}

TEST(PluginEnumerations, CollimatedModelListIsTheCoreTableWithItsDefault)
{
  // Surface Irradiance's Collimated Model: the core table's models in order
  // (values 0..n-1, vtkSurfaceIrradiance passes them through as
  // translucency::CollimatedModel), their labels and help lines, then
  // "Default (by light kind)" (vtkSurfaceIrradiance::COLLIMATED_DEFAULT = n),
  // which is the property's default; its documentation states the default
  // per light kind as the core's table gives it (issue 33).
  const std::string xml = ReadText(SurfaceIrradianceXml);
  ASSERT_FALSE(xml.empty()) << "cannot read " << SurfaceIrradianceXml;
  const std::string proxy = Element(xml, "SourceProxy", "SurfaceIrradiance");
  ASSERT_FALSE(proxy.empty()) << "no SourceProxy SurfaceIrradiance in " << SurfaceIrradianceXml;
  const std::string property = Element(proxy, "IntVectorProperty", "CollimatedModel");
  ASSERT_FALSE(property.empty()) << "no IntVectorProperty CollimatedModel";
  const std::vector<Entry> entries = EnumerationEntries(property);
  const auto& table = translucency::GetCollimatedModelTable();
  ASSERT_EQ(entries.size(), table.size() + 1)
    << "the models of translucency::GetCollimatedModelTable() and the default";
  for (std::size_t k = 0; k < table.size(); ++k)
  {
    EXPECT_EQ(static_cast<std::size_t>(table[k].Model), k) << "the table is in the enum's order";
    EXPECT_EQ(entries[k].Value, std::to_string(k)) << table[k].Name;
    EXPECT_EQ(entries[k].Text, table[k].Label) << "entry " << k;
    EXPECT_EQ(entries[k].Info, table[k].Help) << "entry " << k;
  }
  const std::string defaultValue = std::to_string(table.size());
  EXPECT_EQ(entries.back().Value, defaultValue);
  EXPECT_EQ(entries.back().Text, "Default (by light kind)");
  EXPECT_EQ(Attributes(property, 0)["default_values"], defaultValue)
    << "the plugin's default is the default by light kind";
  std::string documentation = Content(property, "Documentation");
  for (char& c : documentation)
  {
    c = c == '\n' ? ' ' : c;
  }
  EXPECT_NE(documentation.find(translucency::DescribeCollimatedDefaults()), std::string::npos)
    << "the documentation of CollimatedModel in " << SurfaceIrradianceXml
    << " must state the defaults as the core table gives them: \""
    << translucency::DescribeCollimatedDefaults() << "\"";
}

TEST(PluginEnumerations, CollimatedDefaultTableDecidesInItsOrder)
{
  // One solve has one Robin rule: the first kind of the table that a scene
  // has decides. The pencil beams (known only to Solve Diffusion) must come
  // after the directional kinds, whose choice vtkSurfaceIrradiance makes
  // upstream (it leaves their beams out of the irradiance).
  using translucency::LightKind;
  const auto& rows = translucency::GetCollimatedDefaultTable();
  auto position = [&rows](LightKind kind) {
    for (std::size_t k = 0; k < rows.size(); ++k)
    {
      if (rows[k].Kind == kind)
      {
        return k;
      }
    }
    return rows.size();
  };
  ASSERT_LT(position(LightKind::Pencil), rows.size());
  for (const LightKind kind : { LightKind::Directional, LightKind::Coloured, LightKind::Spot,
         LightKind::Point, LightKind::Uniform })
  {
    EXPECT_LT(position(kind), position(LightKind::Pencil)) << "a light decides before a beam";
  }
  EXPECT_EQ(position(LightKind::None), rows.size() - 1);
  const translucency::LightSource white =
    translucency::DirectionalLight({ 0.0, 0.0, -1.0 }, { 1.0, 1.0, 1.0 });
  const translucency::LightSource coloured =
    translucency::DirectionalLight({ 0.0, 0.0, -1.0 }, { 1.0, 0.5, 0.25 });
  const translucency::LightSource spot = translucency::SpotLight(
    { 0.0, 0.0, 10.0 }, { 0.0, 0.0, -1.0 }, 20.0, 0.0, { 1.0, 1.0, 1.0 });
  const translucency::LightSource point =
    translucency::PointLight({ 0.0, 0.0, 10.0 }, { 1.0, 1.0, 1.0 });
  EXPECT_EQ(translucency::KindOfLight(white), LightKind::Directional);
  EXPECT_EQ(translucency::KindOfLight(coloured), LightKind::Coloured);
  EXPECT_EQ(translucency::KindOfLight(spot), LightKind::Spot);
  EXPECT_EQ(translucency::KindOfLight(point), LightKind::Point);
  using translucency::DefaultCollimatedModel;
  EXPECT_EQ(DefaultCollimatedModel({ white }, true, true),
    DefaultCollimatedModel(LightKind::Directional));
  EXPECT_EQ(DefaultCollimatedModel({ coloured }, false, false),
    DefaultCollimatedModel(LightKind::Coloured));
  EXPECT_EQ(DefaultCollimatedModel({ spot }, false, false), DefaultCollimatedModel(LightKind::Spot));
  EXPECT_EQ(DefaultCollimatedModel({ point }, false, true), DefaultCollimatedModel(LightKind::Point));
  EXPECT_EQ(DefaultCollimatedModel({}, true, true), DefaultCollimatedModel(LightKind::Uniform));
  EXPECT_EQ(DefaultCollimatedModel({}, false, true), DefaultCollimatedModel(LightKind::Pencil));
  EXPECT_EQ(DefaultCollimatedModel({}, false, false), DefaultCollimatedModel(LightKind::None));
  EXPECT_THROW(translucency::GetCollimatedModel("extnded"), translucency::Error);
  EXPECT_EQ(translucency::GetCollimatedModel("Extended-Moments").Model,
    translucency::CollimatedModel::ExtendedMoments);
}

} // namespace
