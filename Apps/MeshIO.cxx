#include "MeshIO.h"
#include "Utilities.h"

#include "vtkSurfaceReader.h"
#include "vtkTetGenReader.h"
#include "vtkTetrahedralizeSurface.h"
#include "vtkTranslucencyMeshConversion.h"

#include "Error.h"
#include "InputFiles.h"
#include "Strings.h"

#include <vtkAlgorithm.h>
#include <vtkCellArray.h>
#include <vtkPolyData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace translucency_app
{

namespace
{
/// Limits of the pre-validation of VTK XML files (see CheckVtkXmlFile).
constexpr double MaxCount = 2147483647.0;  ///< points, cells, tuples: the core's int ids
constexpr double MaxComponents = 1024.0;   ///< components of one array
constexpr int MaxElementDepth = 32;        ///< nesting of XML elements
constexpr double MaxCompressionRatio = 20000.0; ///< uncompressed / compressed bytes of a block

/// One XML start tag: its name and attributes.
struct Tag
{
  std::string Name;
  std::vector<std::pair<std::string, std::string>> Attributes;
  bool Has(const std::string& key) const
  {
    for (const auto& a : this->Attributes)
      if (a.first == key)
        return true;
    return false;
  }
  std::string Get(const std::string& key) const
  {
    for (const auto& a : this->Attributes)
      if (a.first == key)
        return a.second;
    return std::string();
  }
};

/// Scans a VTK XML file and throws translucency::Error naming the file, the
/// element and the attribute at the first inconsistency.
class XmlChecker
{
public:
  XmlChecker(const std::string& path, const std::string& text)
    : Path(path)
    , Text(text)
  {
  }

  void Run(const std::string& expectedType);

private:
  /// Appended arrays to check once the AppendedData element is found.
  struct Pending
  {
    Tag Array;
    double ExpectedBytes;
    uint64_t Offset;
  };

  [[noreturn]] void Fail(const std::string& what) const
  {
    throw translucency::Error("'" + this->Path + "': " + what);
  }
  std::string Element(const Tag& t) const
  {
    std::string name = "<" + t.Name;
    if (t.Has("Name"))
      name += " Name=\"" + translucency::Abbreviate(t.Get("Name"), 40) + "\"";
    return name + ">";
  }
  /// An integer attribute in [lo, hi]; `fallback` if absent and not required.
  double Integer(const Tag& t, const std::string& key, double lo, double hi, bool required,
    double fallback = 0.0) const;
  bool NextTag(size_t& pos, Tag& tag, bool& closing, bool& selfClosing, size_t* tagStart = nullptr);
  void CheckDataArray(const Tag& t, const std::string* content, double tuples);
  void CheckHeader(const Tag& t, const std::vector<uint64_t>& header, bool compressed,
    double expectedBytes, double availableBytes);
  std::vector<unsigned char> DecodeBase64(
    const std::string& text, size_t begin, size_t end, size_t maxBytes) const;
  uint64_t Word(const unsigned char* p) const;
  /// Run, 1: the <VTKFile> element (type, byte order, header type, compressor).
  void CheckRoot(const Tag& tag, const std::string& expectedType);
  /// Run, 2: the elements below <VTKFile> up to </VTKFile> or <AppendedData>
  /// (the inline arrays checked on the way, the appended ones queued); false
  /// if no <Piece> was seen.
  bool WalkElements(size_t pos, const std::string& expectedType);
  /// The points and cells of a <Piece> of a file of type `expectedType`.
  void PieceSizes(const Tag& tag, const std::string& expectedType, double& points, double& cells) const;
  /// Run, 3: the headers of the appended arrays against the <AppendedData> bytes.
  void CheckAppended();
  /// The header words of an appended array starting at byte `begin` of the
  /// file, and the data bytes available after them.
  void AppendedHeader(const Pending& p, size_t begin, std::vector<uint64_t>& header, double& available) const;

  std::string Path;
  const std::string& Text;
  bool BigEndian = false;
  int HeaderBytes = 4;
  std::string Compressor;
  size_t AppendedBegin = std::string::npos; ///< first byte after the '_' marker
  std::string AppendedEncoding;
  std::vector<Pending> Appended;
};

double XmlChecker::Integer(
  const Tag& t, const std::string& key, double lo, double hi, bool required, double fallback) const
{
  if (!t.Has(key))
  {
    if (required)
      this->Fail(this->Element(t) + " has no attribute " + key);
    return fallback;
  }
  const std::string value = t.Get(key);
  std::istringstream is(value);
  long double v = 0;
  is >> v;
  std::string rest;
  is >> rest;
  if (value.empty() || value.find_first_not_of("0123456789+- \t\r\n") != std::string::npos ||
    !rest.empty())
  {
    this->Fail(this->Element(t) + " attribute " + key + "=\"" +
      translucency::Abbreviate(value, 40) + "\" is not an integer");
  }
  if (!(v >= lo && v <= hi))
  {
    std::ostringstream os;
    os << this->Element(t) << " attribute " << key << "=\"" << translucency::Abbreviate(value, 40)
       << "\" is out of range [" << static_cast<long long>(lo) << ", "
       << static_cast<long long>(hi) << "]";
    this->Fail(os.str());
  }
  return static_cast<double>(v);
}

bool XmlChecker::NextTag(size_t& pos, Tag& tag, bool& closing, bool& selfClosing, size_t* tagStart)
{
  const std::string& s = this->Text;
  while (true)
  {
    pos = s.find('<', pos);
    if (pos == std::string::npos)
      return false;
    if (s.compare(pos, 4, "<!--") == 0)
    {
      const size_t end = s.find("-->", pos + 4);
      if (end == std::string::npos)
        this->Fail("an XML comment is not closed");
      pos = end + 3;
      continue;
    }
    if (s.compare(pos, 2, "<?") == 0 || s.compare(pos, 2, "<!") == 0)
    {
      const size_t end = s.find('>', pos + 2);
      if (end == std::string::npos)
        this->Fail("an XML declaration is not closed");
      pos = end + 1;
      continue;
    }
    break;
  }
  if (tagStart)
    *tagStart = pos;
  size_t i = pos + 1;
  closing = i < s.size() && s[i] == '/';
  if (closing)
    ++i;
  const size_t nameBegin = i;
  while (i < s.size() && (std::isalnum(static_cast<unsigned char>(s[i])) || s[i] == '_' ||
                           s[i] == ':' || s[i] == '-' || s[i] == '.'))
    ++i;
  tag.Name = s.substr(nameBegin, i - nameBegin);
  tag.Attributes.clear();
  if (tag.Name.empty())
    this->Fail("malformed XML near byte " + std::to_string(pos));
  selfClosing = false;
  while (true)
  {
    while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i])))
      ++i;
    if (i >= s.size())
      this->Fail("the element <" + tag.Name + "> is not closed (the file is truncated)");
    if (s[i] == '>')
    {
      pos = i + 1;
      return true;
    }
    if (s[i] == '/' && i + 1 < s.size() && s[i + 1] == '>')
    {
      selfClosing = true;
      pos = i + 2;
      return true;
    }
    const size_t keyBegin = i;
    while (i < s.size() && s[i] != '=' && s[i] != '>' && !std::isspace(static_cast<unsigned char>(s[i])))
      ++i;
    const std::string key = s.substr(keyBegin, i - keyBegin);
    while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i])))
      ++i;
    if (i >= s.size() || s[i] != '=' || key.empty())
      this->Fail("malformed attribute '" + translucency::Abbreviate(key, 40) + "' of <" +
        tag.Name + ">");
    ++i;
    while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i])))
      ++i;
    if (i >= s.size() || (s[i] != '"' && s[i] != '\''))
      this->Fail("attribute " + key + " of <" + tag.Name + "> has no quoted value");
    const char quote = s[i];
    const size_t valueEnd = s.find(quote, i + 1);
    if (valueEnd == std::string::npos)
      this->Fail("attribute " + key + " of <" + tag.Name + "> is not closed");
    for (const auto& a : tag.Attributes)
      if (a.first == key)
        this->Fail("<" + tag.Name + "> has attribute " + key + " twice");
    tag.Attributes.emplace_back(key, s.substr(i + 1, valueEnd - i - 1));
    i = valueEnd + 1;
  }
}

std::vector<unsigned char> XmlChecker::DecodeBase64(
  const std::string& text, size_t begin, size_t end, size_t maxBytes) const
{
  static const std::string alphabet =
    "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::vector<unsigned char> out;
  uint32_t buffer = 0;
  int bits = 0;
  for (size_t i = begin; i < end && out.size() < maxBytes; ++i)
  {
    const char c = text[i];
    if (std::isspace(static_cast<unsigned char>(c)))
      continue;
    if (c == '=')
    {
      // The padding of one base64 block (VTK encodes the header apart).
      bits = 0;
      buffer = 0;
      continue;
    }
    const size_t v = alphabet.find(c);
    if (v == std::string::npos)
      break;
    buffer = (buffer << 6) | static_cast<uint32_t>(v);
    bits += 6;
    if (bits >= 8)
    {
      bits -= 8;
      out.push_back(static_cast<unsigned char>((buffer >> bits) & 0xFF));
    }
  }
  return out;
}

uint64_t XmlChecker::Word(const unsigned char* p) const
{
  uint64_t v = 0;
  for (int k = 0; k < this->HeaderBytes; ++k)
  {
    const int byte = this->BigEndian ? k : this->HeaderBytes - 1 - k;
    v = (v << 8) | p[byte];
  }
  return v;
}

void XmlChecker::CheckHeader(const Tag& t, const std::vector<uint64_t>& header, bool compressed,
  double expectedBytes, double availableBytes)
{
  std::ostringstream os;
  if (!compressed)
  {
    const double bytes = static_cast<double>(header[0]);
    if (expectedBytes >= 0.0 && bytes != expectedBytes)
    {
      os << this->Element(t) << " holds " << header[0] << " bytes; its attributes ask for "
         << static_cast<long long>(expectedBytes);
      this->Fail(os.str());
    }
    if (bytes > availableBytes)
    {
      os << this->Element(t) << " claims " << header[0] << " bytes; the file holds only "
         << static_cast<long long>(availableBytes) << " after it (truncated?)";
      this->Fail(os.str());
    }
    return;
  }
  const double blocks = static_cast<double>(header[0]);
  const double blockSize = static_cast<double>(header[1]);
  const double last = static_cast<double>(header[2]);
  const double total = blocks == 0 ? 0.0 : (last == 0 ? blocks * blockSize : (blocks - 1) * blockSize + last);
  if (expectedBytes >= 0.0 && total != expectedBytes)
  {
    os << this->Element(t) << " holds " << static_cast<long long>(total)
       << " bytes (compressed header); its attributes ask for "
       << static_cast<long long>(expectedBytes);
    this->Fail(os.str());
  }
  double compressedTotal = 0.0;
  for (size_t b = 3; b < header.size(); ++b)
    compressedTotal += static_cast<double>(header[b]);
  if (compressedTotal > availableBytes)
  {
    os << this->Element(t) << " claims " << static_cast<long long>(compressedTotal)
       << " compressed bytes; the file holds only " << static_cast<long long>(availableBytes)
       << " after it (truncated?)";
    this->Fail(os.str());
  }
  if (total > MaxCompressionRatio * compressedTotal + 1e6)
  {
    os << this->Element(t) << " claims " << static_cast<long long>(total) << " bytes from "
       << static_cast<long long>(compressedTotal) << " compressed bytes (implausible ratio)";
    this->Fail(os.str());
  }
}

void XmlChecker::CheckDataArray(const Tag& t, const std::string* content, double tuples)
{
  static const std::map<std::string, int> sizes = { { "Int8", 1 }, { "UInt8", 1 }, { "Int16", 2 },
    { "UInt16", 2 }, { "Int32", 4 }, { "UInt32", 4 }, { "Int64", 8 }, { "UInt64", 8 },
    { "Float32", 4 }, { "Float64", 8 }, { "String", 0 }, { "Char", 1 } };
  const std::string type = t.Get("type");
  const auto size = sizes.find(type);
  if (size == sizes.end())
    this->Fail(this->Element(t) + " attribute type=\"" + translucency::Abbreviate(type, 40) +
      "\" is not a VTK XML data type (Int8 ... UInt64, Float32, Float64)");
  const double components = this->Integer(t, "NumberOfComponents", 1, MaxComponents, false, 1);
  tuples = this->Integer(t, "NumberOfTuples", 0, MaxCount, false, tuples);
  const double values = tuples < 0.0 ? -1.0 : tuples * components;
  if (values > MaxCount * 4)
  {
    std::ostringstream os;
    os << this->Element(t) << " would hold " << static_cast<long long>(values)
       << " values (NumberOfTuples x NumberOfComponents): too many";
    this->Fail(os.str());
  }
  const double expectedBytes = values < 0.0 || size->second == 0 ? -1.0 : values * size->second;
  const std::string format = t.Has("format") ? t.Get("format") : "ascii";
  const bool compressed = !this->Compressor.empty();
  if (format == "ascii")
  {
    if (!content)
      return;
    double count = 0;
    bool inToken = false;
    for (const char ch : *content)
    {
      const bool space = std::isspace(static_cast<unsigned char>(ch));
      if (!space && !inToken)
        ++count;
      inToken = !space;
    }
    if (values >= 0.0 && size->second != 0 && count != values)
    {
      std::ostringstream os;
      os << this->Element(t) << " holds " << static_cast<long long>(count)
         << " ascii values; its attributes ask for " << static_cast<long long>(values);
      this->Fail(os.str());
    }
    return;
  }
  if (format == "binary")
  {
    if (!content)
      this->Fail(this->Element(t) + " format=\"binary\" holds no data");
    const double available = 0.75 * static_cast<double>(content->size());
    std::vector<unsigned char> head = this->DecodeBase64(*content, 0, content->size(),
      static_cast<size_t>(3 * this->HeaderBytes));
    if (head.size() < static_cast<size_t>((compressed ? 3 : 1) * this->HeaderBytes))
      this->Fail(this->Element(t) + " format=\"binary\": the data header is truncated");
    std::vector<uint64_t> header;
    if (!compressed)
    {
      header.push_back(this->Word(head.data()));
    }
    else
    {
      const uint64_t blocks = this->Word(head.data());
      if (static_cast<double>(blocks) > available / this->HeaderBytes)
        this->Fail(this->Element(t) + " claims more compressed blocks than the file holds");
      head = this->DecodeBase64(*content, 0, content->size(),
        static_cast<size_t>((3 + blocks) * this->HeaderBytes));
      if (head.size() < (3 + blocks) * this->HeaderBytes)
        this->Fail(this->Element(t) + " format=\"binary\": the block header is truncated");
      for (size_t k = 0; k < 3 + blocks; ++k)
        header.push_back(this->Word(head.data() + k * this->HeaderBytes));
    }
    this->CheckHeader(t, header, compressed, expectedBytes, available);
    return;
  }
  if (format == "appended")
  {
    const double offset = this->Integer(t, "offset", 0, 1e18, true);
    this->Appended.push_back({ t, expectedBytes, static_cast<uint64_t>(offset) });
    return;
  }
  this->Fail(this->Element(t) + " attribute format=\"" + translucency::Abbreviate(format, 40) +
    "\" is not ascii, binary or appended");
}

void XmlChecker::CheckRoot(const Tag& tag, const std::string& expectedType)
{
  const std::string type = tag.Get("type");
  if (type != expectedType)
    this->Fail("<VTKFile> attribute type=\"" + translucency::Abbreviate(type, 40) +
      "\" is not " + expectedType);
  const std::string order = tag.Has("byte_order") ? tag.Get("byte_order") : "LittleEndian";
  if (order != "LittleEndian" && order != "BigEndian")
    this->Fail("<VTKFile> attribute byte_order=\"" + translucency::Abbreviate(order, 40) +
      "\" is not LittleEndian or BigEndian");
  this->BigEndian = order == "BigEndian";
  const std::string headerType = tag.Has("header_type") ? tag.Get("header_type") : "UInt32";
  if (headerType != "UInt32" && headerType != "UInt64")
    this->Fail("<VTKFile> attribute header_type=\"" + translucency::Abbreviate(headerType, 40) +
      "\" is not UInt32 or UInt64");
  this->HeaderBytes = headerType == "UInt64" ? 8 : 4;
  this->Compressor = tag.Get("compressor");
  if (!this->Compressor.empty() && this->Compressor != "vtkZLibDataCompressor" &&
    this->Compressor != "vtkLZ4DataCompressor" && this->Compressor != "vtkLZMADataCompressor")
    this->Fail("<VTKFile> attribute compressor=\"" + translucency::Abbreviate(this->Compressor, 40) +
      "\" is not a VTK compressor");
}

void XmlChecker::PieceSizes(
  const Tag& tag, const std::string& expectedType, double& points, double& cells) const
{
  if (expectedType == "ImageData")
  {
    std::istringstream is(tag.Get("Extent"));
    double e[6];
    for (double& v : e)
      if (!(is >> v) || v < -1e9 || v > 1e9 || v != std::floor(v))
        this->Fail("<Piece> attribute Extent=\"" + translucency::Abbreviate(tag.Get("Extent"), 40) +
          "\" is not six integers");
    double n = 1.0;
    for (int k = 0; k < 3; ++k)
      n *= std::max(0.0, e[2 * k + 1] - e[2 * k] + 1);
    if (n > MaxCount)
      this->Fail("<Piece> attribute Extent=\"" + tag.Get("Extent") + "\" has too many points");
    points = n;
    double c = 1.0;
    for (int k = 0; k < 3; ++k)
      c *= std::max(1.0, e[2 * k + 1] - e[2 * k]);
    cells = n == 0.0 ? 0.0 : c;
  }
  else
  {
    points = this->Integer(tag, "NumberOfPoints", 0, MaxCount, true);
    if (expectedType == "UnstructuredGrid")
      cells = this->Integer(tag, "NumberOfCells", 0, MaxCount, true);
    else
    {
      cells = 0;
      for (const char* key : { "NumberOfVerts", "NumberOfLines", "NumberOfStrips", "NumberOfPolys" })
        cells += this->Integer(tag, key, 0, MaxCount, false, 0);
      if (cells > MaxCount)
        this->Fail("<Piece> holds more than 2^31-1 cells");
    }
  }
}

bool XmlChecker::WalkElements(size_t pos, const std::string& expectedType)
{
  const std::string& s = this->Text;
  Tag tag;
  bool closing = false, selfClosing = false;
  // Elements below <VTKFile>: the number of tuples an array must hold follows
  // from the enclosing <Piece> and section (<Points>, <PointData>, <CellData>, <Cells>).
  std::vector<std::string> stack{ "VTKFile" };
  // The array names of each open element: VTK 9.2's reader segfaults on two
  // arrays of one name in a section (a duplicated <DataArray> line).
  std::vector<std::set<std::string>> names(1);
  double points = -1.0, cells = -1.0;
  bool sawPiece = false;
  // The open <DataArray>: its tag, the tuples it must hold, its character data
  // (the text directly inside it, around any <InformationKey> children).
  Tag array;
  double arrayTuples = -1.0;
  std::string arrayText;
  size_t arrayDepth = 0; // stack size with the open <DataArray> on top; 0: none
  size_t textBegin = pos;
  while (true)
  {
    size_t tagStart = 0;
    if (!this->NextTag(pos, tag, closing, selfClosing, &tagStart))
      this->Fail("the file ends inside <" + stack.back() + "> (truncated?)");
    if (arrayDepth != 0 && stack.size() == arrayDepth && tagStart > textBegin)
    {
      arrayText.append(s, textBegin, tagStart - textBegin);
    }
    textBegin = pos;
    if (closing)
    {
      if (stack.empty() || stack.back() != tag.Name)
        this->Fail("</" + tag.Name + "> does not close <" + (stack.empty() ? "" : stack.back()) + ">");
      if (arrayDepth != 0 && stack.size() == arrayDepth)
      {
        this->CheckDataArray(array, &arrayText, arrayTuples);
        arrayDepth = 0;
        arrayText.clear();
      }
      stack.pop_back();
      names.pop_back();
      if (stack.empty())
        break;
      continue;
    }
    if (tag.Name == "AppendedData")
    {
      this->AppendedEncoding = tag.Has("encoding") ? tag.Get("encoding") : "raw";
      if (this->AppendedEncoding != "raw" && this->AppendedEncoding != "base64")
        this->Fail("<AppendedData> attribute encoding=\"" +
          translucency::Abbreviate(this->AppendedEncoding, 40) + "\" is not raw or base64");
      const size_t marker = s.find('_', pos);
      if (marker == std::string::npos)
        this->Fail("<AppendedData> has no '_' marker (truncated?)");
      this->AppendedBegin = marker + 1;
      break; // the rest is data
    }
    if (stack.size() >= static_cast<size_t>(MaxElementDepth))
      this->Fail("XML elements nested deeper than " + std::to_string(MaxElementDepth));
    if (tag.Name == "Piece")
    {
      sawPiece = true;
      this->PieceSizes(tag, expectedType, points, cells);
    }
    if ((tag.Name == "DataArray" || tag.Name == "Array") && arrayDepth == 0 && tag.Has("Name") &&
      !names.back().insert(tag.Get("Name")).second)
      this->Fail(this->Element(tag) + " appears twice in <" + stack.back() +
        "> (two arrays of one name: a duplicated line?)");
    if (tag.Name == "DataArray" && arrayDepth == 0)
    {
      if (!sawPiece && std::find(stack.begin(), stack.end(), "FieldData") == stack.end())
        this->Fail("<DataArray> outside a <Piece>");
      // The tuples this array must hold, where the format fixes it.
      double tuples = -1.0;
      const std::string& section = stack.back();
      const std::string name = tag.Get("Name");
      if (section == "Points" || section == "PointData")
        tuples = points;
      else if (section == "CellData")
        tuples = cells;
      else if (section == "Cells" && (name == "offsets" || name == "types"))
        tuples = cells;
      if (selfClosing)
      {
        this->CheckDataArray(tag, nullptr, tuples);
        continue;
      }
      array = tag;
      arrayTuples = tuples;
      arrayText.clear();
      stack.push_back(tag.Name);
      names.emplace_back();
      arrayDepth = stack.size();
      continue;
    }
    if (!selfClosing)
    {
      stack.push_back(tag.Name);
      names.emplace_back();
    }
  }
  return sawPiece;
}

void XmlChecker::AppendedHeader(
  const Pending& p, size_t begin, std::vector<uint64_t>& header, double& available) const
{
  const std::string& s = this->Text;
  const bool compressed = !this->Compressor.empty();
  const size_t hb = static_cast<size_t>(this->HeaderBytes);
  if (this->AppendedEncoding == "raw")
  {
    available = static_cast<double>(s.size() - begin);
    if (available < (compressed ? 3 : 1) * hb)
      this->Fail(this->Element(p.Array) + ": the data header is truncated");
    const auto* bytes = reinterpret_cast<const unsigned char*>(s.data() + begin);
    header.push_back(this->Word(bytes));
    if (compressed)
    {
      if (static_cast<double>(header[0]) > available / hb)
        this->Fail(this->Element(p.Array) + " claims more compressed blocks than the file holds");
      if (available < (3 + header[0]) * hb)
        this->Fail(this->Element(p.Array) + ": the block header is truncated");
      for (size_t k = 1; k < 3 + header[0]; ++k)
        header.push_back(this->Word(bytes + k * hb));
    }
    available -= static_cast<double>(header.size() * hb);
  }
  else
  {
    available = 0.75 * static_cast<double>(s.size() - begin);
    std::vector<unsigned char> head = this->DecodeBase64(s, begin, s.size(), 3 * hb);
    if (head.size() < (compressed ? 3 : 1) * hb)
      this->Fail(this->Element(p.Array) + ": the data header is truncated");
    header.push_back(this->Word(head.data()));
    if (compressed)
    {
      if (static_cast<double>(header[0]) > available / hb)
        this->Fail(this->Element(p.Array) + " claims more compressed blocks than the file holds");
      head = this->DecodeBase64(s, begin, s.size(), (3 + header[0]) * hb);
      if (head.size() < (3 + header[0]) * hb)
        this->Fail(this->Element(p.Array) + ": the block header is truncated");
      for (size_t k = 1; k < 3 + header[0]; ++k)
        header.push_back(this->Word(head.data() + k * hb));
    }
  }
}

void XmlChecker::CheckAppended()
{
  const std::string& s = this->Text;
  if (!this->Appended.empty() && this->AppendedBegin == std::string::npos)
    this->Fail("a <DataArray format=\"appended\"> but no <AppendedData>");
  const bool compressed = !this->Compressor.empty();
  for (const Pending& p : this->Appended)
  {
    const double at = static_cast<double>(this->AppendedBegin) + static_cast<double>(p.Offset);
    if (at >= static_cast<double>(s.size()))
    {
      std::ostringstream os;
      os << this->Element(p.Array) << " attribute offset=\"" << p.Offset
         << "\" lies beyond the end of the file (truncated?)";
      this->Fail(os.str());
    }
    std::vector<uint64_t> header;
    double available = 0.0;
    this->AppendedHeader(p, static_cast<size_t>(at), header, available);
    this->CheckHeader(p.Array, header, compressed, p.ExpectedBytes, available);
  }
}

void XmlChecker::Run(const std::string& expectedType)
{
  size_t pos = 0;
  Tag tag;
  bool closing = false, selfClosing = false;
  if (!this->NextTag(pos, tag, closing, selfClosing) || tag.Name != "VTKFile" || closing)
    this->Fail("not a VTK XML file (no <VTKFile> element at its start)");
  this->CheckRoot(tag, expectedType);
  if (!this->WalkElements(pos, expectedType))
    this->Fail("no <Piece> element");
  this->CheckAppended();
}
} // namespace

void CheckVtkXmlFile(const std::string& path)
{
  const std::string ext = Extension(path);
  const std::string type = ext == "vtu" ? "UnstructuredGrid"
    : ext == "vtp"                      ? "PolyData"
    : ext == "vti"                      ? "ImageData"
                                        : "";
  if (type.empty())
    throw translucency::Error("'" + path + "': not a .vtu, .vtp or .vti file");
  // A regular file within the size bound (not a FIFO or /dev/zero).
  const std::string text = translucency::ReadInputFile(path, "mesh file");
  if (text.empty())
    throw translucency::Error("'" + path + "' is empty");
  XmlChecker(path, text).Run(type);
}


namespace
{
/// The cells of a grid read from `path`: every one a VTK_TETRA of four point
/// ids in range, every point finite (vtkTranslucency::ToTetArrays, the check
/// the filters make); here the message names the file.
void CheckTetGrid(vtkUnstructuredGrid* grid, const std::string& path)
{
  std::vector<double> points;
  std::vector<int> tets;
  std::string error;
  if (!vtkTranslucency::ToTetArrays(grid, points, tets, error))
  {
    throw translucency::Error("'" + path + "': " + error);
  }
}

/// The cells and points of a surface read from `path`: the checks of
/// vtkTetrahedralizeSurface (vtkStaticCleanPolyData crashed on a point id out of
/// range), with the file named.
void CheckSurface(vtkPolyData* surface, const std::string& path)
{
  std::string error;
  if (!vtkTranslucency::CheckSurfacePointsAndIds(
        surface, vtkTetrahedralizeSurface::MaxCoordinate, error))
  {
    throw translucency::Error("'" + path + "': " + error);
  }
}

} // namespace

/// Read a surface or tet mesh. Returns a polydata (to tetrahedralize) or a grid.
bool ReadMesh(const std::string& path, vtkSmartPointer<vtkPolyData>& surface,
  vtkSmartPointer<vtkUnstructuredGrid>& grid, std::string& error)
{
  try
  {
    // A regular file within the size bound (not a FIFO or /dev/zero).
    translucency::CheckInputFile(path, "mesh file");
  }
  catch (const translucency::Error& e)
  {
    error = e.what();
    return false;
  }
  std::ifstream probe(path);
  if (!probe)
  {
    error = "cannot open mesh file '" + path + "'";
    return false;
  }
  const std::string ext = Extension(path);
  MessageCollector messages;
  vtkSmartPointer<vtkAlgorithm> reader;
  if (ext == "ply" || ext == "stl" || ext == "obj")
  {
    // Our own reader: VTK 9.2's PLY/STL/OBJ readers crash or hang on damaged files.
    auto r = vtkSmartPointer<vtkSurfaceReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  }
  else if (ext == "vtp")
  {
    auto r = vtkSmartPointer<vtkXMLPolyDataReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  }
  else if (ext == "vtu")
  {
    auto r = vtkSmartPointer<vtkXMLUnstructuredGridReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  }
  else if (ext == "node" || ext == "ele")
  {
    auto r = vtkSmartPointer<vtkTetGenReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  }
  else
  {
    error = "unknown mesh format '." + ext + "' of '" + path +
      "' (use .ply, .stl, .obj, .vtp, .vtu, .node or .ele)";
    return false;
  }
  if (ext == "vtp" || ext == "vtu")
  {
    try
    {
      CheckVtkXmlFile(path);
    }
    catch (const translucency::Error& e)
    {
      error = e.what();
      return false;
    }
  }
  messages.Watch(reader);
  reader->Update();
  vtkDataObject* data = reader->GetOutputDataObject(0);
  if (!messages.Errors.empty())
  {
    // vtkSurfaceReader's messages already start with the file's name.
    const std::string last = messages.Last();
    error = last.rfind("'" + path + "'", 0) == 0 ? last : "cannot read '" + path + "': " + last;
    return false;
  }
  if (auto* poly = vtkPolyData::SafeDownCast(data))
  {
    surface = poly;
    try
    {
      CheckSurface(surface, path);
    }
    catch (const translucency::Error& e)
    {
      error = e.what();
      return false;
    }
  }
  else if (auto* ug = vtkUnstructuredGrid::SafeDownCast(data))
  {
    grid = ug;
    try
    {
      CheckTetGrid(grid, path);
    }
    catch (const translucency::Error& e)
    {
      error = e.what();
      return false;
    }
  }
  if ((surface && surface->GetNumberOfCells() == 0) || (grid && grid->GetNumberOfCells() == 0) ||
    (!surface && !grid))
  {
    error = "'" + path + "' holds no cells";
    return false;
  }
  return true;
}

void GridToCoreArrays(vtkUnstructuredGrid* grid, std::vector<double>& points, std::vector<int>& tets)
{
  std::string error;
  if (!vtkTranslucency::ToTetArrays(grid, points, tets, error))
  {
    throw translucency::Error(error);
  }
}

} // namespace translucency_app
