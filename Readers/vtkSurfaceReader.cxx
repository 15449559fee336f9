#include "vtkSurfaceReader.h"
#include "vtkTranslucencyNumbers.h"

#include "vtkCellArray.h"
#include "vtkDoubleArray.h"
#include "vtkFloatArray.h"
#include "vtkIdTypeArray.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkTranslucencyCommunicator.h"
#include "vtkTranslucencyOutputGuard.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <string_view>
#include <system_error>
#include <unordered_map>
#include <vector>

vtkStandardNewMacro(vtkSurfaceReader);

namespace
{
//------------------------------------------------------------------------------
// Errors, lines, tokens, numbers.

/// A problem in the file: `Where` is "line N" or "byte offset N" (or empty).
struct ParseError
{
  std::string Where;
  std::string What;
};

[[noreturn]] void FailAtLine(size_t line, const std::string& what)
{
  throw ParseError{ "line " + std::to_string(line), what };
}

[[noreturn]] void FailAtByte(size_t offset, const std::string& what)
{
  throw ParseError{ "byte offset " + std::to_string(offset), what };
}

[[noreturn]] void Fail(const std::string& what)
{
  throw ParseError{ std::string(), what };
}

/// A token made printable and short enough to quote in a message.
std::string Quote(std::string_view token)
{
  constexpr size_t maxLength = 40;
  std::string quoted = "'";
  for (size_t i = 0; i < token.size() && i < maxLength; ++i)
  {
    const unsigned char c = static_cast<unsigned char>(token[i]);
    quoted += (c >= 32 && c < 127) ? static_cast<char>(c) : '?';
  }
  if (token.size() > maxLength)
  {
    quoted += "...";
  }
  return quoted + "'";
}

std::string Number(double v)
{
  char buffer[32];
  const auto r = std::to_chars(buffer, buffer + sizeof(buffer), v);
  return std::string(buffer, r.ptr);
}

/// The file as lines, numbered from 1, without their "\n" or "\r\n".
class LineReader
{
public:
  LineReader(std::string_view text, size_t start, size_t firstLine)
    : Text(text)
    , Pos(start)
    , Line(firstLine - 1)
  {
  }
  bool Next(std::string_view& line)
  {
    if (this->Pos >= this->Text.size())
    {
      return false;
    }
    const size_t end = this->Text.find('\n', this->Pos);
    const size_t stop = end == std::string_view::npos ? this->Text.size() : end;
    line = this->Text.substr(this->Pos, stop - this->Pos);
    if (!line.empty() && line.back() == '\r')
    {
      line.remove_suffix(1);
    }
    this->Pos = end == std::string_view::npos ? this->Text.size() : end + 1;
    ++this->Line;
    return true;
  }
  /// The next line holding anything but blanks; false at the end of the file.
  bool NextNonBlank(std::string_view& line)
  {
    while (this->Next(line))
    {
      if (line.find_first_not_of(" \t\r\f\v") != std::string_view::npos)
      {
        return true;
      }
    }
    return false;
  }
  size_t LineNumber() const { return this->Line; }
  size_t Position() const { return this->Pos; }

private:
  std::string_view Text;
  size_t Pos;
  size_t Line;
};

/// Splits a line at blanks (space, tab, CR, FF, VT).
void Tokenize(std::string_view line, std::vector<std::string_view>& tokens)
{
  tokens.clear();
  size_t i = 0;
  auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; };
  while (i < line.size())
  {
    while (i < line.size() && blank(line[i]))
    {
      ++i;
    }
    const size_t start = i;
    while (i < line.size() && !blank(line[i]))
    {
      ++i;
    }
    if (i > start)
    {
      tokens.push_back(line.substr(start, i - start));
    }
  }
}

/// The whole token as a decimal integer (an optional leading '+').
bool ParseInteger(std::string_view token, long long& value)
{
  return vtkTranslucencyNumbers::ParseWhole(token, value);
}

/// The whole token as a decimal unsigned integer.
bool ParseUnsigned(std::string_view token, unsigned long long& value)
{
  return vtkTranslucencyNumbers::ParseWhole(token, value);
}

/// The whole token as a finite real number; `error` says why not.
bool ParseFinite(std::string_view token, double& value, std::string& error)
{
  const std::string_view digits = vtkTranslucencyNumbers::StripPlus(token);
  const char* first = digits.data();
  const char* last = first + digits.size();
  const auto r = std::from_chars(first, last, value);
  if (r.ec == std::errc::result_out_of_range)
  {
    error = Quote(token) + " is out of the range of a double";
    return false;
  }
  if (r.ec != std::errc() || r.ptr != last || first == last)
  {
    error = Quote(token) + " is not a number";
    return false;
  }
  if (!std::isfinite(value))
  {
    error = Quote(token) + " is not a finite number";
    return false;
  }
  return true;
}

/// The file's bytes. Regular files only: a FIFO or a device could block forever.
std::string ReadWholeFile(const std::string& path)
{
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (status.type() == std::filesystem::file_type::not_found)
  {
    Fail("the file does not exist");
  }
  if (ec)
  {
    Fail("the file cannot be accessed (" + ec.message() + ")");
  }
  if (!std::filesystem::is_regular_file(status))
  {
    Fail("not a regular file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in)
  {
    Fail("cannot open the file");
  }
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0)
  {
    Fail("cannot tell the file's size");
  }
  in.seekg(0, std::ios::beg);
  std::string bytes(static_cast<size_t>(size), '\0');
  if (size > 0 && !in.read(&bytes[0], size))
  {
    Fail("cannot read the file");
  }
  return bytes;
}

/// A surface as read: points (x, y, z) and polygons (offsets into connectivity).
struct Surface
{
  std::vector<double> Points;
  bool SinglePrecision = false;
  std::vector<vtkIdType> Offsets{ 0 };
  std::vector<vtkIdType> Connectivity;
};

//------------------------------------------------------------------------------
// PLY.

enum class PlyType
{
  Int8,
  UInt8,
  Int16,
  UInt16,
  Int32,
  UInt32,
  Float32,
  Float64
};

struct PlyTypeInfo
{
  const char* Name;
  const char* AlternativeName;
  PlyType Type;
  int Size;
  bool Integer;
  double Min;
  double Max;
};

const PlyTypeInfo PlyTypes[] = {
  { "char", "int8", PlyType::Int8, 1, true, -128.0, 127.0 },
  { "uchar", "uint8", PlyType::UInt8, 1, true, 0.0, 255.0 },
  { "short", "int16", PlyType::Int16, 2, true, -32768.0, 32767.0 },
  { "ushort", "uint16", PlyType::UInt16, 2, true, 0.0, 65535.0 },
  { "int", "int32", PlyType::Int32, 4, true, -2147483648.0, 2147483647.0 },
  { "uint", "uint32", PlyType::UInt32, 4, true, 0.0, 4294967295.0 },
  { "float", "float32", PlyType::Float32, 4, false, -3.4028234663852886e38, 3.4028234663852886e38 },
  { "double", "float64", PlyType::Float64, 8, false, -1.7976931348623157e308,
    1.7976931348623157e308 },
};

const PlyTypeInfo* FindPlyType(std::string_view name)
{
  for (const PlyTypeInfo& t : PlyTypes)
  {
    if (name == t.Name || name == t.AlternativeName)
    {
      return &t;
    }
  }
  return nullptr;
}

struct PlyProperty
{
  std::string Name;
  bool IsList = false;
  const PlyTypeInfo* CountType = nullptr; // lists only
  const PlyTypeInfo* Type = nullptr;      // the value (or list item) type
};

struct PlyElement
{
  std::string Name;
  unsigned long long Count = 0;
  size_t HeaderLine = 0;
  std::vector<PlyProperty> Properties;
};

enum class PlyFormat
{
  Ascii,
  LittleEndian,
  BigEndian
};

bool HostIsLittleEndian()
{
  const std::uint16_t one = 1;
  unsigned char first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

/// The value of type T stored in the bytes at `b`, as a double.
template <typename T>
double BytesAs(const unsigned char* b)
{
  T v;
  std::memcpy(&v, b, sizeof v);
  return static_cast<double>(v);
}

/// A binary value at `p` (bounds already checked) as a double.
double ReadBinary(const char* p, const PlyTypeInfo& type, bool swap)
{
  unsigned char b[8];
  std::memcpy(b, p, type.Size);
  if (swap)
  {
    std::reverse(b, b + type.Size);
  }
  switch (type.Type)
  {
    case PlyType::Int8:
      return BytesAs<std::int8_t>(b);
    case PlyType::UInt8:
      return BytesAs<std::uint8_t>(b);
    case PlyType::Int16:
      return BytesAs<std::int16_t>(b);
    case PlyType::UInt16:
      return BytesAs<std::uint16_t>(b);
    case PlyType::Int32:
      return BytesAs<std::int32_t>(b);
    case PlyType::UInt32:
      return BytesAs<std::uint32_t>(b);
    case PlyType::Float32:
      return BytesAs<float>(b);
    case PlyType::Float64:
      return BytesAs<double>(b);
  }
  return 0.0;
}

/// Reads one PLY file's header; returns the offset of the first data byte.
size_t ReadPlyHeader(const std::string& bytes, PlyFormat& format, std::vector<PlyElement>& elements,
  size_t& dataLine)
{
  LineReader lines(bytes, 0, 1);
  std::string_view line;
  std::vector<std::string_view> tokens;
  if (!lines.Next(line) || line != "ply")
  {
    FailAtLine(1, "not a PLY file: the first line must be 'ply', found " + Quote(line));
  }
  bool haveFormat = false;
  for (;;)
  {
    if (!lines.Next(line))
    {
      Fail("the header has no 'end_header' line (truncated?)");
    }
    const size_t n = lines.LineNumber();
    Tokenize(line, tokens);
    if (tokens.empty())
    {
      FailAtLine(n, "blank line in the header");
    }
    const std::string_view key = tokens[0];
    if (key == "comment" || key == "obj_info")
    {
      continue;
    }
    if (key == "end_header")
    {
      if (tokens.size() != 1)
      {
        FailAtLine(n, "unexpected text after 'end_header'");
      }
      break;
    }
    if (key == "format")
    {
      if (haveFormat)
      {
        FailAtLine(n, "a second 'format' line");
      }
      if (tokens.size() != 3 || tokens[2] != "1.0")
      {
        FailAtLine(n, "expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'");
      }
      if (tokens[1] == "ascii")
      {
        format = PlyFormat::Ascii;
      }
      else if (tokens[1] == "binary_little_endian")
      {
        format = PlyFormat::LittleEndian;
      }
      else if (tokens[1] == "binary_big_endian")
      {
        format = PlyFormat::BigEndian;
      }
      else
      {
        FailAtLine(n, "unknown format " + Quote(tokens[1]));
      }
      haveFormat = true;
    }
    else if (key == "element")
    {
      if (tokens.size() != 3)
      {
        FailAtLine(n, "expected 'element <name> <count>'");
      }
      PlyElement element;
      element.Name = std::string(tokens[1]);
      element.HeaderLine = n;
      if (!ParseUnsigned(tokens[2], element.Count))
      {
        FailAtLine(n,
          "the count " + Quote(tokens[2]) + " of element " + Quote(tokens[1]) +
            " is not a non-negative integer");
      }
      for (const PlyElement& other : elements)
      {
        if (other.Name == element.Name)
        {
          FailAtLine(n, "element " + Quote(element.Name) + " is declared twice");
        }
      }
      elements.push_back(element);
    }
    else if (key == "property")
    {
      if (elements.empty())
      {
        FailAtLine(n, "a 'property' line before any 'element' line");
      }
      PlyProperty property;
      if (tokens.size() >= 2 && tokens[1] == "list")
      {
        if (tokens.size() != 5)
        {
          FailAtLine(n, "expected 'property list <count type> <item type> <name>'");
        }
        property.IsList = true;
        property.CountType = FindPlyType(tokens[2]);
        property.Type = FindPlyType(tokens[3]);
        if (!property.CountType || !property.CountType->Integer)
        {
          FailAtLine(n, "the list count type " + Quote(tokens[2]) + " is not an integer type");
        }
        if (!property.Type)
        {
          FailAtLine(n, "unknown type " + Quote(tokens[3]));
        }
        property.Name = std::string(tokens[4]);
      }
      else
      {
        if (tokens.size() != 3)
        {
          FailAtLine(n, "expected 'property <type> <name>'");
        }
        property.Type = FindPlyType(tokens[1]);
        if (!property.Type)
        {
          FailAtLine(n, "unknown type " + Quote(tokens[1]));
        }
        property.Name = std::string(tokens[2]);
      }
      for (const PlyProperty& other : elements.back().Properties)
      {
        if (other.Name == property.Name)
        {
          FailAtLine(n,
            "property " + Quote(property.Name) + " of element " + Quote(elements.back().Name) +
              " is declared twice");
        }
      }
      elements.back().Properties.push_back(property);
    }
    else
    {
      FailAtLine(n, "unknown header keyword " + Quote(key));
    }
  }
  if (!haveFormat)
  {
    Fail("the header has no 'format' line");
  }
  dataLine = lines.LineNumber() + 1;
  return lines.Position();
}

/// Where the vertex coordinates and face indices are among the properties.
struct PlyLayout
{
  const PlyElement* Vertex = nullptr;
  int Coordinate[3] = { -1, -1, -1 }; // property index of x, y, z
  const PlyElement* Face = nullptr;
  int Indices = -1; // property index of vertex_indices
};

PlyLayout FindPlyLayout(const std::vector<PlyElement>& elements)
{
  PlyLayout layout;
  for (const PlyElement& element : elements)
  {
    if (element.Name == "vertex")
    {
      layout.Vertex = &element;
      const char* names[3] = { "x", "y", "z" };
      for (size_t p = 0; p < element.Properties.size(); ++p)
      {
        for (int k = 0; k < 3; ++k)
        {
          if (element.Properties[p].Name == names[k])
          {
            if (element.Properties[p].IsList)
            {
              FailAtLine(element.HeaderLine,
                std::string("the vertex property '") + names[k] + "' is a list");
            }
            layout.Coordinate[k] = static_cast<int>(p);
          }
        }
      }
      for (int k = 0; k < 3; ++k)
      {
        if (layout.Coordinate[k] < 0)
        {
          FailAtLine(element.HeaderLine,
            std::string("the 'vertex' element has no property '") + names[k] + "'");
        }
      }
    }
    else if (element.Name == "face")
    {
      layout.Face = &element;
      for (size_t p = 0; p < element.Properties.size(); ++p)
      {
        const PlyProperty& property = element.Properties[p];
        if (property.Name == "vertex_indices" || property.Name == "vertex_index")
        {
          if (!property.IsList)
          {
            FailAtLine(element.HeaderLine, "the face property " + Quote(property.Name) + " is not a list");
          }
          if (!property.Type->Integer)
          {
            FailAtLine(element.HeaderLine,
              "the face indices have the non-integer type '" + std::string(property.Type->Name) + "'");
          }
          if (layout.Indices >= 0)
          {
            FailAtLine(element.HeaderLine, "the 'face' element has two vertex index lists");
          }
          layout.Indices = static_cast<int>(p);
        }
      }
      if (layout.Indices < 0 && element.Count > 0)
      {
        FailAtLine(element.HeaderLine, "the 'face' element has no 'vertex_indices' list");
      }
    }
  }
  if (!layout.Vertex)
  {
    Fail("the header declares no 'vertex' element");
  }
  return layout;
}

/// Checks a vertex coordinate and a face index against their meaning.
struct PlyChecks
{
  unsigned long long NumberOfVertices;

  std::string Coordinate(unsigned long long vertex, int k, double value) const
  {
    if (!std::isfinite(value))
    {
      return "vertex " + std::to_string(vertex) + " has the non-finite coordinate " +
        std::string(1, "xyz"[k]) + " = " + Number(value);
    }
    return {};
  }
  std::string Index(unsigned long long face, double value) const
  {
    if (!(value >= 0.0) || !(value < static_cast<double>(this->NumberOfVertices)))
    {
      return "face " + std::to_string(face) + " refers to vertex " + Number(value) +
        ", out of range [0, " + std::to_string(this->NumberOfVertices) + ")";
    }
    return {};
  }
  static std::string CornerCount(unsigned long long face, double count)
  {
    if (count < 3)
    {
      return "face " + std::to_string(face) + " has " + Number(count) +
        " vertices (a polygon needs at least 3)";
    }
    return {};
  }
};

void ReadPlyBinary(const std::string& bytes, size_t pos, bool bigEndian,
  const std::vector<PlyElement>& elements, const PlyLayout& layout, Surface& surface)
{
  const bool swap = bigEndian == HostIsLittleEndian();
  const size_t size = bytes.size();
  const PlyChecks checks{ layout.Vertex->Count };
  for (const PlyElement& element : elements)
  {
    size_t minBytes = 0;
    for (const PlyProperty& property : element.Properties)
    {
      minBytes += property.IsList ? property.CountType->Size : property.Type->Size;
    }
    if (element.Count > 0 && minBytes == 0)
    {
      FailAtLine(element.HeaderLine,
        "element " + Quote(element.Name) + " declares " + std::to_string(element.Count) +
          " items but no properties");
    }
    if (element.Count > 0 && element.Count > (size - pos) / minBytes)
    {
      FailAtLine(element.HeaderLine,
        "element " + Quote(element.Name) + " declares " + std::to_string(element.Count) +
          " items of at least " + std::to_string(minBytes) + " bytes, but only " +
          std::to_string(size - pos) + " bytes are left in the file at byte offset " +
          std::to_string(pos) + " (truncated, or a wrong count)");
    }
    const bool isVertex = &element == layout.Vertex;
    const bool isFace = &element == layout.Face;
    if (isVertex)
    {
      surface.Points.reserve(3 * element.Count);
    }
    if (isFace)
    {
      surface.Offsets.reserve(element.Count + 1);
    }
    for (unsigned long long item = 0; item < element.Count; ++item)
    {
      double xyz[3] = { 0.0, 0.0, 0.0 };
      for (size_t p = 0; p < element.Properties.size(); ++p)
      {
        const PlyProperty& property = element.Properties[p];
        if (property.IsList)
        {
          const PlyTypeInfo& countType = *property.CountType;
          if (size - pos < static_cast<size_t>(countType.Size))
          {
            FailAtByte(pos,
              "the file ends inside " + element.Name + " " + std::to_string(item) + " (truncated)");
          }
          const double count = ReadBinary(bytes.data() + pos, countType, swap);
          const size_t countAt = pos;
          pos += countType.Size;
          if (count < 0)
          {
            FailAtByte(countAt,
              element.Name + " " + std::to_string(item) + " has the negative list count " +
                Number(count));
          }
          const size_t itemBytes = static_cast<size_t>(count) * property.Type->Size;
          if (itemBytes > size - pos)
          {
            FailAtByte(countAt,
              element.Name + " " + std::to_string(item) + " lists " + Number(count) +
                " values, more than the file holds (truncated, or a wrong count)");
          }
          if (isFace && static_cast<int>(p) == layout.Indices)
          {
            std::string error = PlyChecks::CornerCount(item, count);
            if (!error.empty())
            {
              FailAtByte(countAt, error);
            }
            for (size_t k = 0; k < static_cast<size_t>(count); ++k)
            {
              const double index = ReadBinary(bytes.data() + pos, *property.Type, swap);
              error = checks.Index(item, index);
              if (!error.empty())
              {
                FailAtByte(pos, error);
              }
              surface.Connectivity.push_back(static_cast<vtkIdType>(index));
              pos += property.Type->Size;
            }
            surface.Offsets.push_back(static_cast<vtkIdType>(surface.Connectivity.size()));
          }
          else
          {
            pos += itemBytes;
          }
        }
        else
        {
          const PlyTypeInfo& type = *property.Type;
          if (size - pos < static_cast<size_t>(type.Size))
          {
            FailAtByte(pos,
              "the file ends inside " + element.Name + " " + std::to_string(item) + " (truncated)");
          }
          if (isVertex)
          {
            for (int k = 0; k < 3; ++k)
            {
              if (layout.Coordinate[k] == static_cast<int>(p))
              {
                xyz[k] = ReadBinary(bytes.data() + pos, type, swap);
                const std::string error = checks.Coordinate(item, k, xyz[k]);
                if (!error.empty())
                {
                  FailAtByte(pos, error);
                }
              }
            }
          }
          pos += type.Size;
        }
      }
      if (isVertex)
      {
        surface.Points.insert(surface.Points.end(), xyz, xyz + 3);
      }
    }
  }
  if (pos != size)
  {
    FailAtByte(pos,
      std::to_string(size - pos) +
        " bytes follow the last element (a count or a type in the header is wrong)");
  }
}

/// An ASCII value of `type`: integers must be integers in range, reals finite in the type.
double ParsePlyAscii(std::string_view token, const PlyTypeInfo& type, size_t line,
  const std::string& what)
{
  if (type.Integer)
  {
    long long value;
    if (!ParseInteger(token, value))
    {
      FailAtLine(line, what + ": " + Quote(token) + " is not an integer");
    }
    const double v = static_cast<double>(value);
    if (v < type.Min || v > type.Max)
    {
      FailAtLine(line,
        what + ": " + Quote(token) + " is out of the range of its type '" + type.Name + "'");
    }
    return v;
  }
  double value;
  std::string error;
  if (!ParseFinite(token, value, error))
  {
    FailAtLine(line, what + ": " + error);
  }
  if (type.Type == PlyType::Float32 && !std::isfinite(static_cast<float>(value)))
  {
    FailAtLine(line, what + ": " + Quote(token) + " is out of the range of its type 'float'");
  }
  return type.Type == PlyType::Float32 ? static_cast<double>(static_cast<float>(value)) : value;
}

void ReadPlyAscii(const std::string& bytes, size_t pos, size_t firstLine,
  const std::vector<PlyElement>& elements, const PlyLayout& layout, Surface& surface)
{
  LineReader lines(bytes, pos, firstLine);
  std::string_view line;
  std::vector<std::string_view> tokens;
  const PlyChecks checks{ layout.Vertex->Count };
  for (const PlyElement& element : elements)
  {
    if (element.Count > 0 && element.Properties.empty())
    {
      FailAtLine(element.HeaderLine,
        "element " + Quote(element.Name) + " declares " + std::to_string(element.Count) +
          " items but no properties");
    }
    // Each item is a line of at least one value: 2 bytes ("0\n") or more.
    const size_t left = bytes.size() - lines.Position();
    if (element.Count > 0 && element.Count > left / 2 + 1)
    {
      FailAtLine(element.HeaderLine,
        "element " + Quote(element.Name) + " declares " + std::to_string(element.Count) +
          " items, but only " + std::to_string(left) +
          " bytes are left in the file (truncated, or a wrong count)");
    }
    const bool isVertex = &element == layout.Vertex;
    const bool isFace = &element == layout.Face;
    if (isVertex)
    {
      surface.Points.reserve(3 * element.Count);
    }
    if (isFace)
    {
      surface.Offsets.reserve(element.Count + 1);
    }
    for (unsigned long long item = 0; item < element.Count; ++item)
    {
      if (!lines.NextNonBlank(line))
      {
        FailAtLine(lines.LineNumber(),
          "the file ends after " + std::to_string(item) + " of the " +
            std::to_string(element.Count) + " '" + element.Name + "' items (truncated)");
      }
      const size_t n = lines.LineNumber();
      const std::string what = element.Name + " " + std::to_string(item);
      Tokenize(line, tokens);
      size_t t = 0;
      auto next = [&](const PlyProperty& property) {
        if (t >= tokens.size())
        {
          FailAtLine(n, what + ": the line ends before property " + Quote(property.Name));
        }
        return tokens[t++];
      };
      double xyz[3] = { 0.0, 0.0, 0.0 };
      for (size_t p = 0; p < element.Properties.size(); ++p)
      {
        const PlyProperty& property = element.Properties[p];
        if (property.IsList)
        {
          const double count = ParsePlyAscii(next(property), *property.CountType, n, what);
          if (count < 0)
          {
            FailAtLine(n, what + " has the negative list count " + Number(count));
          }
          if (count > static_cast<double>(tokens.size() - t))
          {
            FailAtLine(n,
              what + " lists " + Number(count) + " values but the line holds only " +
                std::to_string(tokens.size() - t));
          }
          const bool indices = isFace && static_cast<int>(p) == layout.Indices;
          if (indices)
          {
            const std::string error = PlyChecks::CornerCount(item, count);
            if (!error.empty())
            {
              FailAtLine(n, error);
            }
          }
          for (size_t k = 0; k < static_cast<size_t>(count); ++k)
          {
            const double value = ParsePlyAscii(next(property), *property.Type, n, what);
            if (indices)
            {
              const std::string error = checks.Index(item, value);
              if (!error.empty())
              {
                FailAtLine(n, error);
              }
              surface.Connectivity.push_back(static_cast<vtkIdType>(value));
            }
          }
          if (indices)
          {
            surface.Offsets.push_back(static_cast<vtkIdType>(surface.Connectivity.size()));
          }
        }
        else
        {
          const double value = ParsePlyAscii(next(property), *property.Type, n, what);
          for (int k = 0; isVertex && k < 3; ++k)
          {
            if (layout.Coordinate[k] == static_cast<int>(p))
            {
              xyz[k] = value;
            }
          }
        }
      }
      if (t != tokens.size())
      {
        FailAtLine(n,
          what + ": " + std::to_string(tokens.size() - t) +
            " values more than the header declares, first " + Quote(tokens[t]));
      }
      if (isVertex)
      {
        surface.Points.insert(surface.Points.end(), xyz, xyz + 3);
      }
    }
  }
  if (lines.NextNonBlank(line))
  {
    FailAtLine(lines.LineNumber(),
      "data after the last element, " + Quote(line) + " (a count in the header is wrong)");
  }
}

void ReadPly(const std::string& bytes, Surface& surface)
{
  PlyFormat format = PlyFormat::Ascii;
  std::vector<PlyElement> elements;
  size_t dataLine = 0;
  const size_t pos = ReadPlyHeader(bytes, format, elements, dataLine);
  const PlyLayout layout = FindPlyLayout(elements);
  surface.SinglePrecision = true;
  for (int k = 0; k < 3; ++k)
  {
    const PlyTypeInfo& type = *layout.Vertex->Properties[layout.Coordinate[k]].Type;
    if (type.Type == PlyType::Float64 || type.Type == PlyType::Int32 ||
      type.Type == PlyType::UInt32)
    {
      surface.SinglePrecision = false;
    }
  }
  if (format == PlyFormat::Ascii)
  {
    ReadPlyAscii(bytes, pos, dataLine, elements, layout, surface);
  }
  else
  {
    ReadPlyBinary(bytes, pos, format == PlyFormat::BigEndian, elements, layout, surface);
  }
}

//------------------------------------------------------------------------------
// STL.

/// Merges exactly coincident points (+0 and -0 alike), keeping the first.
class PointMerger
{
public:
  explicit PointMerger(Surface& surface)
    : Target(surface)
  {
  }
  vtkIdType Insert(const float p[3])
  {
    Key key;
    for (int k = 0; k < 3; ++k)
    {
      const float v = p[k] == 0.0f ? 0.0f : p[k];
      std::memcpy(&key.Bits[k], &v, 4);
    }
    const auto found = this->Ids.emplace(key, static_cast<vtkIdType>(this->Target.Points.size() / 3));
    if (found.second)
    {
      this->Target.Points.insert(this->Target.Points.end(), { p[0], p[1], p[2] });
    }
    return found.first->second;
  }

private:
  struct Key
  {
    std::uint32_t Bits[3];
    bool operator==(const Key& o) const
    {
      return this->Bits[0] == o.Bits[0] && this->Bits[1] == o.Bits[1] && this->Bits[2] == o.Bits[2];
    }
  };
  struct Hash
  {
    size_t operator()(const Key& k) const
    {
      std::uint64_t h = k.Bits[0];
      h = h * 0x9E3779B97F4A7C15ull ^ k.Bits[1];
      h = h * 0x9E3779B97F4A7C15ull ^ k.Bits[2];
      return static_cast<size_t>(h ^ (h >> 29));
    }
  };
  Surface& Target;
  std::unordered_map<Key, vtkIdType, Hash> Ids;
};

void ReadStlBinary(const std::string& bytes, Surface& surface)
{
  if (bytes.size() < 84)
  {
    Fail("too short for a binary STL file (" + std::to_string(bytes.size()) +
      " bytes, the header alone is 84) and it does not start with 'solid'");
  }
  std::uint32_t count;
  std::memcpy(&count, bytes.data() + 80, 4);
  if (!HostIsLittleEndian())
  {
    unsigned char b[4];
    std::memcpy(b, &count, 4);
    std::reverse(b, b + 4);
    std::memcpy(&count, b, 4);
  }
  const unsigned long long expected = 84ull + 50ull * count;
  if (expected != bytes.size())
  {
    FailAtByte(80,
      "binary STL: the header declares " + std::to_string(count) + " triangles, which take " +
        std::to_string(expected) + " bytes, but the file has " + std::to_string(bytes.size()) +
        " bytes (truncated, or a wrong count)");
  }
  surface.SinglePrecision = true;
  surface.Offsets.reserve(count + 1);
  surface.Connectivity.reserve(3 * static_cast<size_t>(count));
  PointMerger merger(surface);
  for (std::uint32_t t = 0; t < count; ++t)
  {
    const size_t base = 84 + 50 * static_cast<size_t>(t);
    for (int corner = 0; corner < 3; ++corner)
    {
      float p[3];
      const size_t at = base + 12 + 12 * corner;
      for (int k = 0; k < 3; ++k)
      {
        p[k] = static_cast<float>(ReadBinary(bytes.data() + at + 4 * k, PlyTypes[6], !HostIsLittleEndian()));
        if (!std::isfinite(p[k]))
        {
          FailAtByte(at + 4 * k,
            "triangle " + std::to_string(t) + " has the non-finite coordinate " + Number(p[k]));
        }
      }
      surface.Connectivity.push_back(merger.Insert(p));
    }
    surface.Offsets.push_back(static_cast<vtkIdType>(surface.Connectivity.size()));
  }
}

void ReadStlAscii(const std::string& bytes, Surface& surface)
{
  surface.SinglePrecision = true;
  PointMerger merger(surface);
  LineReader lines(bytes, 0, 1);
  std::string_view line;
  std::vector<std::string_view> tokens;
  enum class State
  {
    OutsideSolid,
    InSolid,
    InFacet,
    InLoop,
    AfterLoop
  };
  State state = State::OutsideSolid;
  size_t facet = 0;
  size_t corners = 0;
  bool anySolid = false;
  while (lines.NextNonBlank(line))
  {
    const size_t n = lines.LineNumber();
    Tokenize(line, tokens);
    const std::string_view key = tokens[0];
    auto expect = [&](const char* what) {
      FailAtLine(n, std::string("expected ") + what + ", found " + Quote(line));
    };
    switch (state)
    {
      case State::OutsideSolid:
        if (key != "solid")
        {
          expect("'solid'");
        }
        state = State::InSolid;
        anySolid = true;
        break;
      case State::InSolid:
        if (key == "endsolid")
        {
          state = State::OutsideSolid;
          break;
        }
        if (key != "facet" || tokens.size() != 5 || tokens[1] != "normal")
        {
          expect("'facet normal <nx> <ny> <nz>' or 'endsolid'");
        }
        for (int k = 2; k < 5; ++k)
        {
          double v;
          std::string error;
          if (!ParseFinite(tokens[k], v, error) && error.find("not a number") != std::string::npos)
          {
            FailAtLine(n, "facet " + std::to_string(facet) + " normal: " + error);
          }
        }
        state = State::InFacet;
        break;
      case State::InFacet:
        if (key != "outer" || tokens.size() != 2 || tokens[1] != "loop")
        {
          expect("'outer loop'");
        }
        state = State::InLoop;
        corners = 0;
        break;
      case State::InLoop:
        if (key == "endloop" && tokens.size() == 1)
        {
          if (corners < 3)
          {
            FailAtLine(n,
              "facet " + std::to_string(facet) + " has " + std::to_string(corners) +
                " vertices (a polygon needs at least 3)");
          }
          surface.Offsets.push_back(static_cast<vtkIdType>(surface.Connectivity.size()));
          state = State::AfterLoop;
          break;
        }
        if (key != "vertex" || tokens.size() != 4)
        {
          expect("'vertex <x> <y> <z>' or 'endloop'");
        }
        {
          float p[3];
          for (int k = 0; k < 3; ++k)
          {
            double v;
            std::string error;
            if (!ParseFinite(tokens[k + 1], v, error))
            {
              FailAtLine(n, "facet " + std::to_string(facet) + ": " + error);
            }
            p[k] = static_cast<float>(v);
            if (!std::isfinite(p[k]))
            {
              FailAtLine(n,
                "facet " + std::to_string(facet) + ": " + Quote(tokens[k + 1]) +
                  " is out of the range of a float");
            }
          }
          surface.Connectivity.push_back(merger.Insert(p));
          ++corners;
        }
        break;
      case State::AfterLoop:
        if (key != "endfacet" || tokens.size() != 1)
        {
          expect("'endfacet'");
        }
        ++facet;
        state = State::InSolid;
        break;
    }
  }
  if (!anySolid)
  {
    Fail("the ASCII STL file is empty");
  }
  if (state != State::OutsideSolid)
  {
    FailAtLine(lines.LineNumber(), "the file ends before 'endsolid' (truncated)");
  }
}

void ReadStl(const std::string& bytes, Surface& surface)
{
  // Binary when the size matches the declared count (some binary headers start
  // with "solid" too), ASCII when the text starts with "solid" and holds no NUL.
  if (bytes.size() >= 84)
  {
    std::uint32_t count;
    std::memcpy(&count, bytes.data() + 80, 4);
    if (HostIsLittleEndian() && 84ull + 50ull * count == bytes.size())
    {
      ReadStlBinary(bytes, surface);
      return;
    }
  }
  const size_t start = bytes.find_first_not_of(" \t\r\n");
  const bool text = start != std::string::npos && bytes.compare(start, 5, "solid") == 0 &&
    bytes.find('\0') == std::string::npos;
  if (text)
  {
    ReadStlAscii(bytes, surface);
  }
  else
  {
    ReadStlBinary(bytes, surface);
  }
}

//------------------------------------------------------------------------------
// OBJ.

/// ReadObj: the corner `token` of face `face` (line n): v, v/vt, v/vt/vn or
/// v//vn, relative (negative) indices resolved against `counts` (vertices,
/// texture coordinates, normals defined so far); 0 for a missing index.
void ResolveObjCorner(std::string_view token, size_t face, size_t n, const long long counts[3],
  long long resolved[3])
{
  // v, v/vt, v/vt/vn or v//vn.
  std::string_view parts[3];
  int numParts = 0;
  std::string_view rest = token;
  for (;;)
  {
    const size_t slash = rest.find('/');
    if (numParts == 3)
    {
      FailAtLine(n, "face " + std::to_string(face) + ": bad corner " + Quote(token));
    }
    parts[numParts++] = rest.substr(0, slash);
    if (slash == std::string_view::npos)
    {
      break;
    }
    rest = rest.substr(slash + 1);
  }
  for (int part = 0; part < numParts; ++part)
  {
    if (part == 1 && parts[1].empty() && numParts == 3)
    {
      continue; // v//vn
    }
    long long index;
    if (!ParseInteger(parts[part], index) || index == 0)
    {
      FailAtLine(n,
        "face " + std::to_string(face) + ": bad corner " + Quote(token) +
          " (indices are non-zero integers)");
    }
    if (index < 0)
    {
      if (index < -counts[part])
      {
        FailAtLine(n,
          "face " + std::to_string(face) + ": the relative index " + std::to_string(index) +
            " in " + Quote(token) + " reaches before the first of the " +
            std::to_string(counts[part]) + " defined so far");
      }
      index = counts[part] + index + 1;
    }
    resolved[part] = index;
  }
}

void ReadObj(const std::string& bytes, Surface& surface)
{
  LineReader lines(bytes, 0, 1);
  std::string_view line;
  std::vector<std::string_view> tokens;
  std::vector<size_t> faceLines; // for messages about indices checked at the end
  long long texCoords = 0, normals = 0;
  long long maxTexCoord = 0, maxNormal = 0;
  size_t maxTexCoordLine = 0, maxNormalLine = 0;
  while (lines.Next(line))
  {
    const size_t n = lines.LineNumber();
    const size_t hash = line.find('#');
    if (hash != std::string_view::npos)
    {
      line = line.substr(0, hash);
    }
    Tokenize(line, tokens);
    if (tokens.empty())
    {
      continue;
    }
    const std::string_view key = tokens[0];
    if (key == "v")
    {
      if (tokens.size() < 4 || tokens.size() > 8)
      {
        FailAtLine(n, "a 'v' line needs 3 coordinates (and optionally w or r g b), found " +
            std::to_string(tokens.size() - 1) + " values");
      }
      for (size_t k = 1; k < tokens.size(); ++k)
      {
        double v;
        std::string error;
        if (!ParseFinite(tokens[k], v, error))
        {
          FailAtLine(n, "vertex " + std::to_string(surface.Points.size() / 3) + ": " + error);
        }
        if (k <= 3)
        {
          surface.Points.push_back(v);
        }
      }
    }
    else if (key == "vt" || key == "vn")
    {
      for (size_t k = 1; k < tokens.size(); ++k)
      {
        double v;
        std::string error;
        if (!ParseFinite(tokens[k], v, error))
        {
          FailAtLine(n, Quote(key) + " line: " + error);
        }
      }
      ++(key == "vt" ? texCoords : normals);
    }
    else if (key == "f")
    {
      const size_t face = faceLines.size();
      if (tokens.size() < 4)
      {
        FailAtLine(n,
          "face " + std::to_string(face) + " has " + std::to_string(tokens.size() - 1) +
            " vertices (a polygon needs at least 3)");
      }
      const long long numPoints = static_cast<long long>(surface.Points.size() / 3);
      for (size_t k = 1; k < tokens.size(); ++k)
      {
        const long long counts[3] = { numPoints, texCoords, normals };
        long long resolved[3] = { 0, 0, 0 };
        ResolveObjCorner(tokens[k], face, n, counts, resolved);
        surface.Connectivity.push_back(static_cast<vtkIdType>(resolved[0] - 1));
        if (resolved[1] > maxTexCoord)
        {
          maxTexCoord = resolved[1];
          maxTexCoordLine = n;
        }
        if (resolved[2] > maxNormal)
        {
          maxNormal = resolved[2];
          maxNormalLine = n;
        }
      }
      surface.Offsets.push_back(static_cast<vtkIdType>(surface.Connectivity.size()));
      faceLines.push_back(n);
    }
  }
  // Positive indices may refer to vertices defined later in the file.
  const vtkIdType numPoints = static_cast<vtkIdType>(surface.Points.size() / 3);
  for (size_t face = 0; face + 1 < surface.Offsets.size(); ++face)
  {
    for (vtkIdType c = surface.Offsets[face]; c < surface.Offsets[face + 1]; ++c)
    {
      if (surface.Connectivity[c] >= numPoints)
      {
        FailAtLine(faceLines[face],
          "face " + std::to_string(face) + " refers to vertex " +
            std::to_string(surface.Connectivity[c] + 1) + " but the file defines " +
            std::to_string(numPoints));
      }
    }
  }
  if (maxTexCoord > texCoords)
  {
    FailAtLine(maxTexCoordLine,
      "a face refers to texture coordinate " + std::to_string(maxTexCoord) +
        " but the file defines " + std::to_string(texCoords));
  }
  if (maxNormal > normals)
  {
    FailAtLine(maxNormalLine,
      "a face refers to normal " + std::to_string(maxNormal) + " but the file defines " +
        std::to_string(normals));
  }
}

std::string LowerExtension(const std::string& path)
{
  const std::string name = std::filesystem::path(path).filename().string();
  const size_t dot = name.rfind('.');
  std::string ext = dot == std::string::npos ? std::string() : name.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
    [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

int FormatFromExtension(const std::string& path)
{
  const std::string ext = LowerExtension(path);
  if (ext == "ply")
  {
    return vtkSurfaceReader::FORMAT_PLY;
  }
  if (ext == "stl")
  {
    return vtkSurfaceReader::FORMAT_STL;
  }
  if (ext == "obj")
  {
    return vtkSurfaceReader::FORMAT_OBJ;
  }
  return vtkSurfaceReader::FORMAT_FROM_EXTENSION;
}
} // namespace

//------------------------------------------------------------------------------
vtkSurfaceReader::vtkSurfaceReader()
{
  this->SetNumberOfInputPorts(0);
}

//------------------------------------------------------------------------------
int vtkSurfaceReader::CanReadFile(const char* fileName)
{
  if (!fileName || FormatFromExtension(fileName) == FORMAT_FROM_EXTENSION)
  {
    return 0;
  }
  std::error_code ec;
  return std::filesystem::is_regular_file(fileName, ec) ? 1 : 0;
}

//------------------------------------------------------------------------------
int vtkSurfaceReader::RequestInformation(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector)
{
  // Rank 0 reads the whole file, the others return an empty piece: all of
  // them execute, so that they agree on the outcome (RunReaderAgreed).
  vtkTranslucencyCommunicator::ExecuteEveryPiece(outputVector);
  return 1;
}

//------------------------------------------------------------------------------
int vtkSurfaceReader::RequestData(
  vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector)
{
  // Under MPI every rank agrees on the outcome (rank 0 reads the file).
  return vtkTranslucencyCommunicator::RunReaderAgreed(
    this, outputVector, [this, outputVector]() { return this->ReadPiece(outputVector); });
}

//------------------------------------------------------------------------------
int vtkSurfaceReader::ReadPiece(vtkInformationVector* outputVector)
{
  vtkTranslucencyOutputGuard outputs(outputVector); // clean empty outputs on any failure
  vtkPolyData* output = vtkPolyData::GetData(outputVector, 0);
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  if (outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER()) &&
    outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER()) > 0)
  {
    return outputs.Succeed(); // the whole surface is piece 0: an empty piece
  }
  if (this->FileName.empty())
  {
    vtkErrorMacro(<< "no file name given");
    return 0;
  }
  const int format =
    this->Format != FORMAT_FROM_EXTENSION ? this->Format : FormatFromExtension(this->FileName);
  if (format == FORMAT_FROM_EXTENSION)
  {
    vtkErrorMacro(<< "'" << this->FileName
                  << "': unknown surface format (the name must end in .ply, .stl or .obj)");
    return 0;
  }
  Surface surface;
  try
  {
    const std::string bytes = ReadWholeFile(this->FileName);
    switch (format)
    {
      case FORMAT_PLY:
        ReadPly(bytes, surface);
        break;
      case FORMAT_STL:
        ReadStl(bytes, surface);
        break;
      default:
        ReadObj(bytes, surface);
        break;
    }
  }
  catch (const ParseError& error)
  {
    vtkErrorMacro(<< "'" << this->FileName << "'"
                  << (error.Where.empty() ? std::string() : ", " + error.Where) << ": "
                  << error.What);
    return 0;
  }
  catch (const std::bad_alloc&)
  {
    vtkErrorMacro(<< "'" << this->FileName << "': out of memory");
    return 0;
  }

  const vtkIdType numPoints = static_cast<vtkIdType>(surface.Points.size() / 3);
  vtkNew<vtkPoints> points;
  if (surface.SinglePrecision)
  {
    vtkNew<vtkFloatArray> xyz;
    xyz->SetNumberOfComponents(3);
    xyz->SetNumberOfTuples(numPoints);
    float* out = xyz->GetPointer(0);
    std::transform(surface.Points.begin(), surface.Points.end(), out,
      [](double v) { return static_cast<float>(v); });
    points->SetData(xyz);
  }
  else
  {
    vtkNew<vtkDoubleArray> xyz;
    xyz->SetNumberOfComponents(3);
    xyz->SetNumberOfTuples(numPoints);
    std::copy(surface.Points.begin(), surface.Points.end(), xyz->GetPointer(0));
    points->SetData(xyz);
  }
  vtkNew<vtkIdTypeArray> offsets;
  offsets->SetNumberOfTuples(static_cast<vtkIdType>(surface.Offsets.size()));
  std::copy(surface.Offsets.begin(), surface.Offsets.end(), offsets->GetPointer(0));
  vtkNew<vtkIdTypeArray> connectivity;
  connectivity->SetNumberOfTuples(static_cast<vtkIdType>(surface.Connectivity.size()));
  std::copy(surface.Connectivity.begin(), surface.Connectivity.end(), connectivity->GetPointer(0));
  vtkNew<vtkCellArray> polys;
  polys->SetData(offsets, connectivity);
  output->SetPoints(points);
  output->SetPolys(polys);
  return outputs.Succeed();
}

//------------------------------------------------------------------------------
void vtkSurfaceReader::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << this->FileName << "\n";
  os << indent << "Format: " << this->Format << "\n";
}
