#include "vtkMaterialTableReader.h"

#include "InputFiles.h"
#include "OpticalProperties.h"
#include "Strings.h"

#include <vtkDoubleArray.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkStringArray.h>
#include <vtkStreamingDemandDrivenPipeline.h>
#include <vtkTable.h>

#include "vtkTranslucencyCommunicator.h"
#include "vtkTranslucencyOutputGuard.h"
#include "vtk_nlohmannjson.h"
#include VTK_NLOHMANN_JSON(json.hpp)

#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>

vtkStandardNewMacro(vtkMaterialTableReader);

namespace
{
using json = nlohmann::json;

[[noreturn]] void Fail(const std::string& fileName, const std::string& what)
{
  throw std::runtime_error("material table '" + fileName + "': " + what);
}

/// A JSON value for a message: dumped (the nesting is bounded by
/// translucency::MaxJsonNesting before parsing) and cut to 80 characters.
std::string Short(const json& v)
{
  return translucency::Abbreviate(v.dump());
}

std::string EntryPrefix(size_t index, const json& entry)
{
  std::ostringstream os;
  os << "entry " << index;
  if (entry.is_object() && entry.contains("name") && entry["name"].is_string())
  {
    os << " (\"" << translucency::Abbreviate(entry["name"].get<std::string>()) << "\")";
  }
  return os.str();
}

/// A non-negative finite number (a JSON number), else a message.
double NonNegative(const std::string& fileName, const std::string& where, const json& v)
{
  if (!v.is_number())
  {
    Fail(fileName, where + " must be a number, not " + Short(v));
  }
  const double x = v.get<double>();
  if (!std::isfinite(x) || x < 0.0 || x > 1e6)
  {
    std::ostringstream os;
    os << where << " must be finite, >= 0 and <= 1e6, not " << Short(v);
    Fail(fileName, os.str());
  }
  return x;
}

/// ReadMaterialTable: the file read (a regular file within the size bound,
/// not a FIFO or /dev/zero), its nesting bounded, parsed as JSON and checked
/// to be an object with a "materials" array.
json ParseMaterialFile(const std::string& fileName)
{
  if (fileName.empty())
  {
    throw std::runtime_error("material table: no file name given");
  }
  std::string text;
  try
  {
    text = translucency::ReadInputFile(fileName, "material table");
  }
  catch (const translucency::Error& e)
  {
    throw std::runtime_error(e.what());
  }
  if (translucency::JsonNestingDepth(text) > translucency::MaxJsonNesting)
  {
    Fail(fileName, "arrays/objects nested deeper than " +
        std::to_string(translucency::MaxJsonNesting) + " levels");
  }
  json root;
  try
  {
    root = json::parse(text);
  }
  catch (const std::exception& e)
  {
    Fail(fileName, std::string("not valid JSON: ") + translucency::Abbreviate(e.what(), 160));
  }
  if (!root.is_object() || !root.contains("materials") || !root["materials"].is_array())
  {
    Fail(fileName, "must hold a JSON object {\"units\": \"1/mm\", \"materials\": [...]}");
  }
  return root;
}

/// ReadMaterialTable: the factor from the file's "units" to 1/mm (1 if
/// none is given).
double UnitScale(const std::string& fileName, const json& root)
{
  if (!root.contains("units"))
  {
    return 1.0;
  }
  const json& u = root["units"];
  const std::string units = u.is_string() ? u.get<std::string>() : u.dump();
  if (units == "1/mm")
    return 1.0;
  if (units == "1/cm")
    return 0.1;
  if (units == "1/m")
    return 0.001;
  Fail(fileName, "\"units\" must be \"1/mm\", \"1/cm\" or \"1/m\", not " + Short(u));
}

/// ReadMaterialTable, one entry: its fields known, its "name" and "id".
void ReadEntryKeys(const std::string& fileName, const std::string& where, const json& e,
  vtkMaterialTableReader::Material& m)
{
  if (!e.is_object())
  {
    Fail(fileName, where + " must be a JSON object, not " + Short(e));
  }
  for (auto it = e.begin(); it != e.end(); ++it)
  {
    static const std::set<std::string> known = { "name", "id", "preset", "absorption",
      "reduced_scattering", "refractive_index" };
    if (!known.count(it.key()))
    {
      Fail(fileName, where + ": unknown field \"" + it.key() + "\"");
    }
  }
  if (e.contains("name"))
  {
    if (!e["name"].is_string() || e["name"].get<std::string>().empty())
    {
      Fail(fileName, where + ": \"name\" must be a non-empty string, not " + Short(e["name"]));
    }
    m.Name = e["name"].get<std::string>();
  }
  if (e.contains("id"))
  {
    const json& id = e["id"];
    if (!id.is_number_integer() || id.get<long long>() < 0 ||
      id.get<long long>() > std::numeric_limits<int>::max())
    {
      Fail(fileName, where + ": \"id\" must be an integer >= 0, not " + Short(id));
    }
    m.Id = id.get<int>();
  }
  if (m.Name.empty() && m.Id < 0 && !e.contains("preset"))
  {
    Fail(fileName, where + " needs a \"name\" or an \"id\"");
  }
}

/// ReadMaterialTable, one entry: the coefficients of its "preset" (and its
/// name when the entry has neither name nor id).
void ReadEntryPreset(const std::string& fileName, const std::string& where, const json& e,
  vtkMaterialTableReader::Material& m)
{
  const bool explicitValues = e.contains("absorption") || e.contains("reduced_scattering") ||
    e.contains("refractive_index");
  if (explicitValues)
  {
    Fail(fileName,
      where + " has both \"preset\" and explicit coefficients: give one or the other");
  }
  if (!e["preset"].is_string())
  {
    Fail(fileName, where + ": \"preset\" must be a preset name (a string), not " +
        Short(e["preset"]));
  }
  try
  {
    const translucency::MaterialPreset& p =
      translucency::FindMaterialPreset(e["preset"].get<std::string>());
    for (int c = 0; c < 3; ++c)
    {
      m.Absorption[c] = p.Absorption[c];
      m.ReducedScattering[c] = p.ReducedScattering[c];
    }
    m.RefractiveIndex = p.RefractiveIndex;
    if (m.Name.empty() && m.Id < 0)
    {
      m.Name = p.Name;
    }
  }
  catch (const std::exception& ex)
  {
    Fail(fileName, where + ": \"preset\": " + ex.what());
  }
}

/// ReadMaterialTable, one entry: its explicit coefficients (in the file's
/// units, scaled to 1/mm by `unitScale`) and refractive index.
void ReadEntryCoefficients(const std::string& fileName, const std::string& where,
  const json& e, double unitScale, vtkMaterialTableReader::Material& m)
{
  if (!e.contains("absorption") || !e.contains("reduced_scattering"))
  {
    Fail(fileName, where + " needs either \"preset\" or both \"absorption\": [r, g, b] and "
                           "\"reduced_scattering\": [r, g, b]");
  }
  auto triple = [&](const char* key, double out[3]) {
    const json& v = e[key];
    if (!v.is_array() || v.size() != 3)
    {
      Fail(fileName, where + ": \"" + key + "\" must be [r, g, b], not " + Short(v));
    }
    for (int c = 0; c < 3; ++c)
    {
      out[c] = unitScale *
        NonNegative(fileName, where + ": \"" + key + "\"[" + std::to_string(c) + "]", v[c]);
    }
  };
  triple("absorption", m.Absorption);
  triple("reduced_scattering", m.ReducedScattering);
  for (int c = 0; c < 3; ++c)
  {
    if (!(m.Absorption[c] + m.ReducedScattering[c] > 0.0))
    {
      Fail(fileName, where + ": absorption + reduced_scattering must be > 0 in channel " +
          std::to_string(c));
    }
  }
  if (e.contains("refractive_index"))
  {
    m.RefractiveIndex = NonNegative(fileName, where + ": \"refractive_index\"",
      e["refractive_index"]);
    // [0.1, 10]: 1e-320 passed "> 0" and gave a NaN fluence.
    if (!(m.RefractiveIndex >= 0.1 && m.RefractiveIndex <= 10.0))
    {
      Fail(fileName, where + ": \"refractive_index\" must be in [0.1, 10], not " +
          Short(e["refractive_index"]));
    }
  }
}
} // namespace

//------------------------------------------------------------------------------
vtkMaterialTableReader::vtkMaterialTableReader()
{
  this->SetNumberOfInputPorts(0);
}

//------------------------------------------------------------------------------
int vtkMaterialTableReader::CanReadFile(const char* fileName)
{
  if (!fileName)
  {
    return 0;
  }
  const std::string f(fileName);
  return f.size() > 5 && f.compare(f.size() - 5, 5, ".json") == 0 ? 1 : 0;
}

//------------------------------------------------------------------------------
std::vector<vtkMaterialTableReader::Material> vtkMaterialTableReader::ReadMaterialTable(
  const std::string& fileName)
{
  const json root = ParseMaterialFile(fileName);
  const double unitScale = UnitScale(fileName, root);
  const json& list = root["materials"];
  if (list.empty())
  {
    Fail(fileName, "\"materials\" is empty");
  }
  std::vector<Material> materials;
  std::set<int> ids;
  std::set<std::string> names;
  for (size_t i = 0; i < list.size(); ++i)
  {
    const json& e = list[i];
    const std::string where = EntryPrefix(i, e);
    Material m;
    ReadEntryKeys(fileName, where, e, m);
    if (e.contains("preset"))
    {
      ReadEntryPreset(fileName, where, e, m);
    }
    else
    {
      ReadEntryCoefficients(fileName, where, e, unitScale, m);
    }
    if (m.Id >= 0 && !ids.insert(m.Id).second)
    {
      Fail(fileName, where + ": duplicate \"id\" " + std::to_string(m.Id));
    }
    if (e.contains("name") && !names.insert(m.Name).second)
    {
      Fail(fileName, where + ": duplicate \"name\" \"" + m.Name + "\"");
    }
    materials.push_back(m);
  }
  return materials;
}

//------------------------------------------------------------------------------
int vtkMaterialTableReader::RequestInformation(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector)
{
  // Rank 0 reads the whole file, the others return an empty piece: all of
  // them execute, so that they agree on the outcome (RunReaderAgreed).
  vtkTranslucencyCommunicator::ExecuteEveryPiece(outputVector);
  return 1;
}

//------------------------------------------------------------------------------
int vtkMaterialTableReader::RequestData(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector)
{
  // Under MPI every rank agrees on the outcome (rank 0 reads the file).
  return vtkTranslucencyCommunicator::RunReaderAgreed(
    this, outputVector, [this, outputVector]() { return this->ReadPiece(outputVector); });
}

//------------------------------------------------------------------------------
int vtkMaterialTableReader::ReadPiece(vtkInformationVector* outputVector)
{
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkTable* output = vtkTable::GetData(outputVector);
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  if (outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER()) &&
    outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER()) > 0)
  {
    return outputs.Succeed(); // the whole table is piece 0: an empty piece
  }
  std::vector<Material> materials;
  try
  {
    materials = ReadMaterialTable(this->FileName);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  const vtkIdType n = static_cast<vtkIdType>(materials.size());
  vtkNew<vtkIntArray> id;
  id->SetName("Id");
  id->SetNumberOfTuples(n);
  vtkNew<vtkStringArray> name;
  name->SetName("Name");
  name->SetNumberOfValues(n);
  vtkNew<vtkDoubleArray> absorption;
  absorption->SetName("AbsorptionCoefficient");
  absorption->SetNumberOfComponents(3);
  absorption->SetNumberOfTuples(n);
  vtkNew<vtkDoubleArray> scattering;
  scattering->SetName("ReducedScatteringCoefficient");
  scattering->SetNumberOfComponents(3);
  scattering->SetNumberOfTuples(n);
  vtkNew<vtkDoubleArray> index;
  index->SetName("RefractiveIndex");
  index->SetNumberOfTuples(n);
  for (vtkIdType i = 0; i < n; ++i)
  {
    const Material& m = materials[i];
    id->SetValue(i, m.Id);
    name->SetValue(i, m.Name);
    absorption->SetTypedTuple(i, m.Absorption);
    scattering->SetTypedTuple(i, m.ReducedScattering);
    index->SetValue(i, m.RefractiveIndex);
  }
  output->AddColumn(id);
  output->AddColumn(name);
  output->AddColumn(absorption);
  output->AddColumn(scattering);
  output->AddColumn(index);
  return outputs.Succeed();
}

//------------------------------------------------------------------------------
void vtkMaterialTableReader::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << this->FileName << "\n";
}
