#include "vtkTetGenReader.h"
#include "vtkTranslucencyNumbers.h"

#include "vtkCellArray.h"
#include "vtkCellData.h"
#include "vtkCellType.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkIdTypeArray.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkTranslucencyCommunicator.h"
#include "vtkTranslucencyOutputGuard.h"
#include "vtkUnstructuredGrid.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

vtkStandardNewMacro(vtkTetGenReader);

namespace
{
/// Lines between two progress reports / abort checks.
constexpr vtkIdType ProgressInterval = 1 << 16;

/// Reports progress in [0, 1]; returns false when the user asked to abort.
using ProgressFunction = std::function<bool(double)>;

//------------------------------------------------------------------------------
// File names.

bool EndsWithIgnoreCase(const std::string& text, std::string_view suffix)
{
  if (text.size() <= suffix.size())
  {
    return false;
  }
  const std::size_t start = text.size() - suffix.size();
  for (std::size_t i = 0; i < suffix.size(); ++i)
  {
    if (std::tolower(static_cast<unsigned char>(text[start + i])) !=
        std::tolower(static_cast<unsigned char>(suffix[i])))
    {
      return false;
    }
  }
  return true;
}

/// The three files of a TetGen mesh, derived from any one of them or from the
/// base name.
struct TetGenFileNames
{
  std::string Node;
  std::string Ele;
  std::string Face;
};

TetGenFileNames DeriveFileNames(const std::string& fileName)
{
  std::string base = fileName;
  for (std::string_view extension : { ".node", ".ele", ".face" })
  {
    if (EndsWithIgnoreCase(base, extension))
    {
      base.resize(base.size() - extension.size());
      break;
    }
  }
  return { base + ".node", base + ".ele", base + ".face" };
}

/// Empty if @a path names an existing regular file, else why it cannot be read.
/// Regular files only: opening a FIFO or a device could block forever.
std::string WhyNotARegularFile(const std::string& path)
{
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (status.type() == std::filesystem::file_type::not_found)
  {
    return "does not exist";
  }
  if (ec)
  {
    return "cannot be accessed (" + ec.message() + ")";
  }
  if (!std::filesystem::is_regular_file(status))
  {
    return "is not a regular file";
  }
  return {};
}

//------------------------------------------------------------------------------
// Tokens and numbers.

/// A token made printable and short enough to quote in a message.
std::string Quote(std::string_view token)
{
  constexpr std::size_t maxLength = 40;
  std::string quoted = "'";
  for (std::size_t i = 0; i < token.size() && i < maxLength; ++i)
  {
    const unsigned char c = static_cast<unsigned char>(token[i]);
    quoted += std::isprint(c) ? static_cast<char>(c) : '?';
  }
  if (token.size() > maxLength)
  {
    quoted += "...";
  }
  return quoted + "'";
}

/// Parses the whole token as a decimal integer (an optional leading '+' is allowed).
bool ParseInteger(std::string_view token, long long& value)
{
  return vtkTranslucencyNumbers::ParseWhole(token, value);
}

/// Parses the whole token as a real number, independently of the C locale.
bool ParseReal(std::string_view token, double& value)
{
  return vtkTranslucencyNumbers::ParseWhole(token, value);
}

//------------------------------------------------------------------------------
/// One ASCII TetGen file read line by line, with comments removed.
class TetGenTextFile
{
public:
  /// @a kind names the file in messages, e.g. "node" for the .node file.
  TetGenTextFile(std::string path, std::string kind)
    : Path(std::move(path))
    , Kind(std::move(kind))
  {
  }

  const std::string& GetPath() const { return this->Path; }

  /// Size of the file in bytes (0 if unknown); bounds memory reservations.
  std::uintmax_t GetSize() const { return this->Size; }

  /// Number of the last line read (1-based, counting comment and blank lines).
  long long GetLineNumber() const { return this->LineNumber; }

  /// The values of the current line.
  const std::vector<std::string_view>& GetTokens() const { return this->Tokens; }

  /// "file '<path>', line <n>", the prefix of every message about the current line.
  std::string Where() const
  {
    return "file '" + this->Path + "', line " + std::to_string(this->LineNumber);
  }

  bool Open(std::string& error)
  {
    std::string reason = WhyNotARegularFile(this->Path);
    if (reason.empty())
    {
      this->Stream.open(this->Path, std::ios::in | std::ios::binary);
      if (!this->Stream)
      {
        reason = "cannot be opened for reading";
      }
    }
    if (!reason.empty())
    {
      error = "The TetGen " + this->Kind + " file '" + this->Path + "' " + reason;
      return false;
    }
    std::error_code ec;
    this->Size = std::filesystem::file_size(this->Path, ec);
    if (ec)
    {
      this->Size = 0;
    }
    return true;
  }

  /// Moves to the next line that holds values. Returns false at the end of
  /// the file or on a read error (then @a error is set).
  bool NextDataLine(std::string& error)
  {
    while (std::getline(this->Stream, this->Buffer))
    {
      ++this->LineNumber;
      this->Tokenize();
      if (!this->Tokens.empty())
      {
        return true;
      }
    }
    this->Tokens.clear();
    if (this->Stream.bad())
    {
      error = "Reading the TetGen " + this->Kind + " file '" + this->Path + "' failed after line " +
        std::to_string(this->LineNumber) + ".";
    }
    return false;
  }

  /// A reservation size for @a count records: never more than the file could
  /// hold, so that a corrupt header cannot exhaust memory.
  vtkIdType Reservation(vtkIdType count) const
  {
    // Every record takes at least a few bytes ("1 2 3 4\n").
    const std::uintmax_t bound = this->Size / 8 + 1;
    return static_cast<vtkIdType>(
      std::min<std::uintmax_t>(static_cast<std::uintmax_t>(count), bound));
  }

  /// A reservation size for @a count records of @a perRecord values each,
  /// bounded by the number of values the file could hold.
  std::size_t ValueReservation(vtkIdType count, std::size_t perRecord) const
  {
    // Every value takes at least two bytes (a digit and a separator).
    const std::uintmax_t bound = this->Size / 2 + 1;
    if (perRecord == 0 || count <= 0)
    {
      return 0;
    }
    const std::uintmax_t records = static_cast<std::uintmax_t>(count);
    if (records > bound / perRecord)
    {
      return static_cast<std::size_t>(bound);
    }
    return static_cast<std::size_t>(records * perRecord);
  }

private:
  void Tokenize()
  {
    std::string_view line(this->Buffer);
    if (this->LineNumber == 1 && line.substr(0, 3) == "\xEF\xBB\xBF")
    {
      line.remove_prefix(3); // UTF-8 byte order mark
    }
    const std::size_t comment = line.find('#');
    if (comment != std::string_view::npos)
    {
      line = line.substr(0, comment);
    }
    this->Tokens.clear();
    auto isSeparator = [](char c) {
      return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f' || c == ',';
    };
    std::size_t i = 0;
    while (i < line.size())
    {
      while (i < line.size() && isSeparator(line[i]))
      {
        ++i;
      }
      const std::size_t start = i;
      while (i < line.size() && !isSeparator(line[i]))
      {
        ++i;
      }
      if (i > start)
      {
        this->Tokens.push_back(line.substr(start, i - start));
      }
    }
  }

  std::string Path;
  std::string Kind;
  std::ifstream Stream;
  std::uintmax_t Size = 0;
  std::string Buffer;
  std::vector<std::string_view> Tokens;
  long long LineNumber = 0;
};

//------------------------------------------------------------------------------
// Field parsing with messages naming file, line and token.

bool GetInteger(const TetGenTextFile& file, std::size_t column, const std::string& what,
                long long& value, std::string& error)
{
  const std::string_view token = file.GetTokens()[column];
  if (!ParseInteger(token, value))
  {
    error = file.Where() + ": malformed number " + Quote(token) + " where " + what +
      " (an integer) was expected.";
    return false;
  }
  return true;
}

bool GetReal(const TetGenTextFile& file, std::size_t column, const std::string& what, double& value,
             std::string& error)
{
  const std::string_view token = file.GetTokens()[column];
  if (!ParseReal(token, value))
  {
    error = file.Where() + ": malformed number " + Quote(token) + " where " + what +
      " (a real number) was expected.";
    return false;
  }
  return true;
}

bool GetMarker(const TetGenTextFile& file, std::size_t column, const std::string& what, int& value,
               std::string& error)
{
  long long wide = 0;
  if (!GetInteger(file, column, what, wide, error))
  {
    return false;
  }
  if (wide < std::numeric_limits<int>::min() || wide > std::numeric_limits<int>::max())
  {
    error = file.Where() + ": " + what + " " + Quote(file.GetTokens()[column]) +
      " is out of the range of a 32-bit integer.";
    return false;
  }
  value = static_cast<int>(wide);
  return true;
}

/// One header field with its name (for messages) and its default when omitted.
struct HeaderField
{
  const char* Name;
  long long Default;
  bool Required;
  long long Value;
};

/// Reads the header line: the fields are non-negative integers; trailing
/// optional fields may be omitted; extra values are ignored.
bool ReadHeader(TetGenTextFile& file, const std::string& layout, std::vector<HeaderField>& fields,
                std::string& error)
{
  if (!file.NextDataLine(error))
  {
    if (error.empty())
    {
      error = "The TetGen file '" + file.GetPath() +
        "' is empty or holds only comments: the header line '" + layout + "' was expected.";
    }
    return false;
  }
  const std::size_t present = file.GetTokens().size();
  for (std::size_t i = 0; i < fields.size(); ++i)
  {
    HeaderField& field = fields[i];
    if (i >= present)
    {
      if (field.Required)
      {
        error = file.Where() + ": the header has " + std::to_string(present) + " values but the " +
          field.Name + " is missing (expected '" + layout + "').";
        return false;
      }
      field.Value = field.Default;
      continue;
    }
    if (!GetInteger(file, i, std::string("the ") + field.Name + " in the header", field.Value,
                    error))
    {
      return false;
    }
    if (field.Value < 0)
    {
      error = file.Where() + ": the " + field.Name + " in the header is negative (" +
        std::to_string(field.Value) + ").";
      return false;
    }
  }
  return true;
}

/// Checks a count against the range of vtkIdType.
bool CheckCount(const TetGenTextFile& file, const HeaderField& field, std::string& error)
{
  if (static_cast<unsigned long long>(field.Value) >
      static_cast<unsigned long long>(std::numeric_limits<vtkIdType>::max() / 16))
  {
    error = file.Where() + ": the " + field.Name + " in the header (" +
      std::to_string(field.Value) + ") is too large.";
    return false;
  }
  return true;
}

/// Checks that a 0/1 header field is 0 or 1.
bool CheckFlag(const TetGenTextFile& file, const HeaderField& field, std::string& error)
{
  if (field.Value != 0 && field.Value != 1)
  {
    error = file.Where() + ": the " + field.Name + " in the header must be 0 or 1, not " +
      std::to_string(field.Value) + ".";
    return false;
  }
  return true;
}

/// The message for a file that ends before record @a index (0-based) of @a count.
std::string TruncatedMessage(const TetGenTextFile& file, const char* record, vtkIdType index,
                             vtkIdType count, long long headerLine)
{
  return "The TetGen file '" + file.GetPath() + "' is truncated: " + record + " " +
    std::to_string(index + 1) + " of " + std::to_string(count) + " (as declared on line " +
    std::to_string(headerLine) + ") was expected on line " +
    std::to_string(file.GetLineNumber() + 1) + ", but the file ends after line " +
    std::to_string(file.GetLineNumber()) + ".";
}

/// The message for a data line with too few values.
std::string ShortLineMessage(const TetGenTextFile& file, std::size_t expected,
                             const std::string& layout)
{
  return file.Where() + ": " + std::to_string(file.GetTokens().size()) + " values were found but " +
    std::to_string(expected) + " are expected (" + layout + ").";
}

/**
 * Reads data line @a index (0-based) of the @a count records of a table:
 * reports progress every ProgressInterval lines (false with @a aborted set
 * when the user aborts), names a truncated file or a line with fewer than
 * @a columns values, and, when @a warnedExtra is given, warns once per file
 * about extra values.
 */
bool NextRecord(TetGenTextFile& file, const char* record, vtkIdType index, vtkIdType count,
                long long headerLine, std::size_t columns, const std::string& layout,
                const ProgressFunction& progress, bool& aborted, vtkObject* self,
                bool* warnedExtra, std::string& error)
{
  if (index % ProgressInterval == 0 && index > 0 &&
      !progress(static_cast<double>(index) / static_cast<double>(count)))
  {
    aborted = true;
    return false;
  }
  if (!file.NextDataLine(error))
  {
    if (error.empty())
    {
      error = TruncatedMessage(file, record, index, count, headerLine);
    }
    return false;
  }
  const std::size_t found = file.GetTokens().size();
  if (found < columns)
  {
    error = ShortLineMessage(file, columns, layout);
    return false;
  }
  if (warnedExtra && found > columns && !*warnedExtra)
  {
    *warnedExtra = true;
    vtkWarningWithObjectMacro(self, << file.Where() << ": " << found
                                    << " values were found but " << columns << " are expected ("
                                    << layout
                                    << "); the extra values are ignored here and on any "
                                       "later line of this file.");
  }
  return true;
}

std::string Columns(std::size_t count, const char* name)
{
  return count == 0 ? std::string()
                    : ", " + std::to_string(count) + " " + name + (count == 1 ? "" : "s");
}

//------------------------------------------------------------------------------
// The .node file.

struct NodeTable
{
  vtkIdType Count = 0;
  long long FirstId = 0;
  std::size_t NumberOfAttributes = 0;
  bool HasMarkers = false;
  vtkNew<vtkDoubleArray> Coordinates;
  std::vector<double> Attributes; // row-major, Count x NumberOfAttributes
  vtkNew<vtkIntArray> Markers;
};

bool ReadNodes(TetGenTextFile& file, NodeTable& nodes, const ProgressFunction& progress,
               bool& aborted, vtkObject* self, std::string& error)
{
  std::vector<HeaderField> header = { { "number of points", 0, true, 0 },
                                      { "dimension", 3, false, 0 },
                                      { "number of attributes", 0, false, 0 },
                                      { "number of boundary markers", 0, false, 0 } };
  if (!ReadHeader(file, "<#points> <dimension (3)> <#attributes> <#boundary markers (0 or 1)>",
                  header, error))
  {
    return false;
  }
  const long long headerLine = file.GetLineNumber();
  if (!CheckCount(file, header[0], error) || !CheckCount(file, header[2], error) ||
      !CheckFlag(file, header[3], error))
  {
    return false;
  }
  if (header[1].Value != 3)
  {
    error = file.Where() + ": the dimension in the header is " + std::to_string(header[1].Value) +
      ", but only 3-dimensional meshes can be read.";
    return false;
  }
  nodes.Count = static_cast<vtkIdType>(header[0].Value);
  nodes.NumberOfAttributes = static_cast<std::size_t>(header[2].Value);
  nodes.HasMarkers = header[3].Value == 1;

  const std::size_t columns = 4 + nodes.NumberOfAttributes + (nodes.HasMarkers ? 1 : 0);
  const std::string layout = "id, x, y, z" + Columns(nodes.NumberOfAttributes, "attribute") +
    (nodes.HasMarkers ? ", boundary marker" : "");

  const vtkIdType reservation = file.Reservation(nodes.Count);
  nodes.Coordinates->SetNumberOfComponents(3);
  nodes.Coordinates->SetName("Points");
  nodes.Coordinates->Allocate(3 * reservation);
  nodes.Attributes.reserve(file.ValueReservation(reservation, nodes.NumberOfAttributes));
  nodes.Markers->SetName("BoundaryMarker");
  if (nodes.HasMarkers)
  {
    nodes.Markers->Allocate(reservation);
  }

  bool warnedExtra = false;
  for (vtkIdType i = 0; i < nodes.Count; ++i)
  {
    if (!NextRecord(file, "node", i, nodes.Count, headerLine, columns, layout, progress,
                    aborted, self, &warnedExtra, error))
    {
      return false;
    }

    long long id = 0;
    if (!GetInteger(file, 0, "the id of node " + std::to_string(i + 1), id, error))
    {
      return false;
    }
    if (i == 0)
    {
      if (id != 0 && id != 1)
      {
        error = file.Where() + ": the first node id is " + std::to_string(id) +
          ", but TetGen numbers nodes from 0 or 1.";
        return false;
      }
      nodes.FirstId = id;
    }
    else if (id != nodes.FirstId + i)
    {
      error = file.Where() + ": node id " + std::to_string(id) + " found where " +
        std::to_string(nodes.FirstId + i) + " was expected (node ids must be consecutive).";
      return false;
    }

    const std::string label = " of node " + std::to_string(id);
    double xyz[3];
    static const char* const axes[3] = { "the x coordinate", "the y coordinate",
                                         "the z coordinate" };
    for (int k = 0; k < 3; ++k)
    {
      if (!GetReal(file, 1 + k, axes[k] + label, xyz[k], error))
      {
        return false;
      }
      if (!std::isfinite(xyz[k]))
      {
        error = file.Where() + ": " + axes[k] + label + " is " + Quote(file.GetTokens()[1 + k]) +
          ", which is not a finite number.";
        return false;
      }
    }
    nodes.Coordinates->InsertNextTuple(xyz);

    for (std::size_t a = 0; a < nodes.NumberOfAttributes; ++a)
    {
      double value = 0.0;
      if (!GetReal(file, 4 + a, "attribute " + std::to_string(a) + label, value, error))
      {
        return false;
      }
      nodes.Attributes.push_back(value);
    }
    if (nodes.HasMarkers)
    {
      int marker = 0;
      if (!GetMarker(file, columns - 1, "the boundary marker" + label, marker, error))
      {
        return false;
      }
      nodes.Markers->InsertNextValue(marker);
    }
  }
  return true;
}

/// "(the .node file '<path>' has nodes 1 to 8)", for messages about bad indices.
std::string NodeRange(const NodeTable& nodes, const std::string& nodePath)
{
  if (nodes.Count == 0)
  {
    return "(the .node file '" + nodePath + "' has no nodes)";
  }
  return "(the .node file '" + nodePath + "' has nodes " + std::to_string(nodes.FirstId) + " to " +
    std::to_string(nodes.FirstId + nodes.Count - 1) + ")";
}

/// Reads column @a column as a node reference of @a owner and converts it to
/// a 0-based point index.
bool GetNodeIndex(const TetGenTextFile& file, std::size_t column, const std::string& owner,
                  const NodeTable& nodes, const std::string& nodePath, vtkIdType& index,
                  std::string& error)
{
  long long id = 0;
  if (!GetInteger(file, column, "node " + std::to_string(column) + " of " + owner, id, error))
  {
    return false;
  }
  // id >= FirstId (0 or 1) is tested first, so the subtraction cannot overflow.
  if (id < nodes.FirstId || id - nodes.FirstId >= static_cast<long long>(nodes.Count))
  {
    error = file.Where() + ": " + owner + " refers to node " + std::to_string(id) +
      ", which does not exist " + NodeRange(nodes, nodePath) + ".";
    return false;
  }
  index = static_cast<vtkIdType>(id - nodes.FirstId);
  return true;
}

//------------------------------------------------------------------------------
// The .ele file.

struct ElementTable
{
  vtkIdType Count = 0;
  int NodesPerElement = 4;
  std::size_t NumberOfAttributes = 0;
  vtkNew<vtkIdTypeArray> Connectivity;
  std::vector<double> Attributes; // row-major, Count x NumberOfAttributes
};

bool ReadElements(TetGenTextFile& file, const NodeTable& nodes, const std::string& nodePath,
                  ElementTable& elements, const ProgressFunction& progress, bool& aborted,
                  vtkObject* self, std::string& error)
{
  std::vector<HeaderField> header = { { "number of tetrahedra", 0, true, 0 },
                                      { "number of nodes per tetrahedron", 4, false, 0 },
                                      { "number of region attributes", 0, false, 0 } };
  if (!ReadHeader(file,
                  "<#tetrahedra> <nodes per tetrahedron (4 or 10)> <#region attributes (0 or 1)>",
                  header, error))
  {
    return false;
  }
  const long long headerLine = file.GetLineNumber();
  if (!CheckCount(file, header[0], error) || !CheckCount(file, header[2], error))
  {
    return false;
  }
  if (header[1].Value != 4 && header[1].Value != 10)
  {
    error = file.Where() + ": the number of nodes per tetrahedron in the header is " +
      std::to_string(header[1].Value) + ", but only 4 or 10 are valid.";
    return false;
  }
  elements.Count = static_cast<vtkIdType>(header[0].Value);
  elements.NodesPerElement = static_cast<int>(header[1].Value);
  elements.NumberOfAttributes = static_cast<std::size_t>(header[2].Value);
  if (elements.NodesPerElement == 10 && elements.Count > 0)
  {
    vtkWarningWithObjectMacro(self, << "The TetGen element file '" << file.GetPath()
                                    << "' holds 10-node (quadratic) tetrahedra; only the 4 "
                                       "corner nodes of each are used.");
  }

  const std::size_t nodesPerElement = static_cast<std::size_t>(elements.NodesPerElement);
  const std::size_t columns = 1 + nodesPerElement + elements.NumberOfAttributes;
  const std::string layout = "id, " + std::to_string(nodesPerElement) + " node ids" +
    Columns(elements.NumberOfAttributes, "region attribute");

  const vtkIdType reservation = file.Reservation(elements.Count);
  elements.Connectivity->Allocate(4 * reservation);
  elements.Attributes.reserve(file.ValueReservation(reservation, elements.NumberOfAttributes));

  bool warnedExtra = false;
  for (vtkIdType i = 0; i < elements.Count; ++i)
  {
    if (!NextRecord(file, "tetrahedron", i, elements.Count, headerLine, columns, layout, progress,
                    aborted, self, &warnedExtra, error))
    {
      return false;
    }

    long long id = 0;
    if (!GetInteger(file, 0, "the id of tetrahedron " + std::to_string(i + 1), id, error))
    {
      return false;
    }
    const std::string owner = "element " + std::to_string(id);
    for (std::size_t k = 0; k < nodesPerElement; ++k)
    {
      vtkIdType index = 0;
      if (!GetNodeIndex(file, 1 + k, owner, nodes, nodePath, index, error))
      {
        return false;
      }
      if (k < 4)
      {
        elements.Connectivity->InsertNextValue(index);
      }
    }
    for (std::size_t a = 0; a < elements.NumberOfAttributes; ++a)
    {
      double value = 0.0;
      if (!GetReal(file, 1 + nodesPerElement + a,
                   "region attribute " + std::to_string(a) + " of " + owner, value, error))
      {
        return false;
      }
      elements.Attributes.push_back(value);
    }
  }
  return true;
}

//------------------------------------------------------------------------------
// The .face file.

struct FaceTable
{
  vtkIdType Count = 0;
  bool HasMarkers = false;
  vtkNew<vtkIntArray> Faces;
  vtkNew<vtkIntArray> Markers;
};

bool ReadFaces(TetGenTextFile& file, const NodeTable& nodes, const std::string& nodePath,
               FaceTable& faces, const ProgressFunction& progress, bool& aborted,
               std::string& error)
{
  std::vector<HeaderField> header = { { "number of faces", 0, true, 0 },
                                      { "number of boundary markers", 0, false, 0 } };
  if (!ReadHeader(file, "<#faces> <#boundary markers (0 or 1)>", header, error))
  {
    return false;
  }
  const long long headerLine = file.GetLineNumber();
  if (!CheckCount(file, header[0], error) || !CheckFlag(file, header[1], error))
  {
    return false;
  }
  faces.Count = static_cast<vtkIdType>(header[0].Value);
  faces.HasMarkers = header[1].Value == 1;

  const std::size_t columns = 4 + (faces.HasMarkers ? 1 : 0);
  const std::string layout =
    std::string("id, 3 node ids") + (faces.HasMarkers ? ", boundary marker" : "");

  const vtkIdType reservation = file.Reservation(faces.Count);
  faces.Faces->SetName("TetGenFaces");
  faces.Faces->SetNumberOfComponents(3);
  faces.Faces->Allocate(3 * reservation);
  faces.Markers->SetName("TetGenFaceMarkers");
  if (faces.HasMarkers)
  {
    faces.Markers->Allocate(reservation);
  }

  for (vtkIdType i = 0; i < faces.Count; ++i)
  {
    if (!NextRecord(file, "face", i, faces.Count, headerLine, columns, layout, progress,
                    aborted, nullptr, nullptr, error))
    {
      return false;
    }
    long long id = 0;
    if (!GetInteger(file, 0, "the id of face " + std::to_string(i + 1), id, error))
    {
      return false;
    }
    const std::string owner = "face " + std::to_string(id);
    int corners[3];
    for (int k = 0; k < 3; ++k)
    {
      vtkIdType index = 0;
      if (!GetNodeIndex(file, 1 + k, owner, nodes, nodePath, index, error))
      {
        return false;
      }
      corners[k] = static_cast<int>(index); // nodes.Count <= INT_MAX, checked by the caller
    }
    faces.Faces->InsertNextTypedTuple(corners);
    if (faces.HasMarkers)
    {
      int marker = 0;
      if (!GetMarker(file, 4, "the boundary marker of " + owner, marker, error))
      {
        return false;
      }
      faces.Markers->InsertNextValue(marker);
    }
  }
  return true;
}

/// Splits a row-major table into one single-component array per column.
void AddColumns(vtkDataSetAttributes* target, const std::vector<double>& table, vtkIdType rows,
                std::size_t columns, const std::string& firstName, const std::string& prefix,
                bool numberFirst)
{
  for (std::size_t c = 0; c < columns; ++c)
  {
    vtkNew<vtkDoubleArray> array;
    const std::string name = (c == 0 && !numberFirst) ? firstName : prefix + std::to_string(c);
    array->SetName(name.c_str());
    array->SetNumberOfTuples(rows);
    for (vtkIdType r = 0; r < rows; ++r)
    {
      array->SetValue(r, table[static_cast<std::size_t>(r) * columns + c]);
    }
    target->AddArray(array);
  }
}
} // anonymous namespace

//------------------------------------------------------------------------------
vtkTetGenReader::vtkTetGenReader()
{
  this->SetNumberOfInputPorts(0);
}

//------------------------------------------------------------------------------
vtkTetGenReader::~vtkTetGenReader()
{
  this->SetFileName(nullptr);
}

//------------------------------------------------------------------------------
int vtkTetGenReader::CanReadFile(const char* fname)
{
  if (!fname || !*fname)
  {
    return 0;
  }
  const TetGenFileNames names = DeriveFileNames(fname);
  std::string error;

  TetGenTextFile nodeFile(names.Node, "node");
  std::vector<HeaderField> nodeHeader = { { "number of points", 0, true, 0 },
                                          { "dimension", 3, false, 0 },
                                          { "number of attributes", 0, false, 0 },
                                          { "number of boundary markers", 0, false, 0 } };
  if (!nodeFile.Open(error) || !ReadHeader(nodeFile, "", nodeHeader, error) ||
      nodeHeader[1].Value != 3 || (nodeHeader[3].Value != 0 && nodeHeader[3].Value != 1))
  {
    return 0;
  }

  TetGenTextFile eleFile(names.Ele, "element");
  std::vector<HeaderField> eleHeader = { { "number of tetrahedra", 0, true, 0 },
                                         { "number of nodes per tetrahedron", 4, false, 0 },
                                         { "number of region attributes", 0, false, 0 } };
  if (!eleFile.Open(error) || !ReadHeader(eleFile, "", eleHeader, error) ||
      (eleHeader[1].Value != 4 && eleHeader[1].Value != 10))
  {
    return 0;
  }
  return 1;
}

//------------------------------------------------------------------------------
int vtkTetGenReader::RequestInformation(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector)
{
  // Rank 0 reads the whole file, the others return an empty piece: all of
  // them execute, so that they agree on the outcome (RunReaderAgreed).
  vtkTranslucencyCommunicator::ExecuteEveryPiece(outputVector);
  return 1;
}

//------------------------------------------------------------------------------
int vtkTetGenReader::RequestData(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector)
{
  // Under MPI every rank agrees on the outcome (rank 0 reads the file).
  return vtkTranslucencyCommunicator::RunReaderAgreed(
    this, outputVector, [this, outputVector]() { return this->ReadPiece(outputVector); });
}

//------------------------------------------------------------------------------
int vtkTetGenReader::ReadPiece(vtkInformationVector* outputVector)
{
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outputVector, 0);
  if (!output)
  {
    vtkErrorMacro(<< "The output is not a vtkUnstructuredGrid.");
    return 0;
  }
  output->Initialize();

  // The whole mesh is piece 0; other pieces stay empty.
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  if (outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER()) &&
      outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER()) > 0)
  {
    return outputs.Succeed();
  }

  if (!this->FileName || !*this->FileName)
  {
    vtkErrorMacro(<< "No FileName was set: give the .node or .ele file of a TetGen mesh, "
                     "or their base name.");
    return 0;
  }

  // Bad input is reported by ReadMesh itself; this only guards against running
  // out of memory on a file too large for this machine.
  try
  {
    return this->ReadMesh(output) ? outputs.Succeed() : 0;
  }
  catch (const std::exception& exception)
  {
    output->Initialize();
    vtkErrorMacro(<< "Reading the TetGen mesh '" << this->FileName
                  << "' failed: " << exception.what());
    return 0;
  }
}

//------------------------------------------------------------------------------
int vtkTetGenReader::ReadMesh(vtkUnstructuredGrid* output)
{
  const TetGenFileNames names = DeriveFileNames(this->FileName);
  std::string error;
  bool aborted = false;

  // Progress: the .node file takes [0, 0.45), the .ele file [0.45, 0.9) and
  // the .face file [0.9, 1).
  auto stage = [this](double start, double width) -> ProgressFunction
  {
    return [this, start, width](double fraction)
    {
      this->UpdateProgress(start + width * fraction);
      return !this->CheckAbort();
    };
  };

  // 1. Open both required files first, so that a missing one is reported at once.
  TetGenTextFile nodeFile(names.Node, "node");
  TetGenTextFile eleFile(names.Ele, "element");
  if (!nodeFile.Open(error) || !eleFile.Open(error))
  {
    vtkErrorMacro(<< error << " (derived from FileName '" << this->FileName << "').");
    return 0;
  }

  // 2. Points and their attributes.
  NodeTable nodes;
  if (!ReadNodes(nodeFile, nodes, stage(0.0, 0.45), aborted, this, error))
  {
    if (aborted)
    {
      return 1;
    }
    vtkErrorMacro(<< error);
    return 0;
  }

  // 3. Tetrahedra and their region attributes.
  ElementTable elements;
  if (!ReadElements(eleFile, nodes, names.Node, elements, stage(0.45, 0.45), aborted, this, error))
  {
    if (aborted)
    {
      return 1;
    }
    vtkErrorMacro(<< error);
    return 0;
  }

  // 4. Boundary faces, when asked for and present.
  FaceTable faces;
  bool haveFaces = false;
  if (this->ReadFaces && WhyNotARegularFile(names.Face).empty())
  {
    if (nodes.Count > static_cast<vtkIdType>(std::numeric_limits<int>::max()))
    {
      vtkWarningMacro(<< "The mesh has " << nodes.Count
                      << " points, more than a vtkIntArray can index; the TetGen face file '"
                      << names.Face << "' is not read.");
    }
    else
    {
      TetGenTextFile faceFile(names.Face, "face");
      if (!faceFile.Open(error))
      {
        vtkErrorMacro(<< error << ".");
        return 0;
      }
      if (!::ReadFaces(faceFile, nodes, names.Node, faces, stage(0.9, 0.1), aborted, error))
      {
        if (aborted)
        {
          return 1;
        }
        vtkErrorMacro(<< error);
        return 0;
      }
      haveFaces = true;
    }
  }

  // 5. Assemble the output only once everything was read without error.
  vtkNew<vtkPoints> points;
  points->SetData(nodes.Coordinates);
  output->SetPoints(points);

  vtkNew<vtkIdTypeArray> offsets;
  offsets->SetNumberOfTuples(elements.Count + 1);
  for (vtkIdType i = 0; i <= elements.Count; ++i)
  {
    offsets->SetValue(i, 4 * i);
  }
  vtkNew<vtkCellArray> cells;
  cells->SetData(offsets, elements.Connectivity);
  output->SetCells(VTK_TETRA, cells);

  AddColumns(output->GetPointData(), nodes.Attributes, nodes.Count, nodes.NumberOfAttributes, "",
             "NodeAttribute", true);
  if (nodes.HasMarkers)
  {
    output->GetPointData()->AddArray(nodes.Markers);
  }
  AddColumns(output->GetCellData(), elements.Attributes, elements.Count,
             elements.NumberOfAttributes, "RegionAttribute", "RegionAttribute", false);
  if (haveFaces)
  {
    output->GetFieldData()->AddArray(faces.Faces);
    if (faces.HasMarkers)
    {
      output->GetFieldData()->AddArray(faces.Markers);
    }
  }
  this->UpdateProgress(1.0);
  return 1;
}

//------------------------------------------------------------------------------
void vtkTetGenReader::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName ? this->FileName : "(none)") << "\n";
  os << indent << "ReadFaces: " << (this->ReadFaces ? "On" : "Off") << "\n";
}
