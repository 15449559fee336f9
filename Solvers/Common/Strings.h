/**
 * @file Strings.h
 * @brief The string helpers every layer shares: case folding of the names
 * users type (solvers, presets, options) and the lists of known names that
 * error messages and help texts show.
 */
#pragma once

#include <algorithm>
#include <cctype>
#include <cstddef>
#include <sstream>
#include <string>
#include <vector>

namespace translucency
{

/// `text` in lower case (ASCII; names are matched case-insensitively).
inline std::string ToLower(std::string text)
{
  std::transform(text.begin(), text.end(), text.begin(),
    [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  return text;
}

/// The names joined by `separator`, e.g. "a, b, c" for error messages.
inline std::string JoinNames(const std::vector<std::string>& names, const std::string& separator = ", ")
{
  std::string joined;
  for (const std::string& name : names)
  {
    joined += (joined.empty() ? "" : separator) + name;
  }
  return joined;
}

/// `text` cut to `maxChars` characters plus "..." if longer: bad values
/// (e.g. a dumped JSON value) go into error messages only this way.
inline std::string Abbreviate(const std::string& text, size_t maxChars = 80)
{
  return text.size() <= maxChars ? text : text.substr(0, maxChars) + "...";
}

/// The deepest nesting of [ ] and { } in JSON `text` (brackets inside strings
/// do not count); a scan without recursion, run before parsing.
inline int JsonNestingDepth(const std::string& text)
{
  int depth = 0, deepest = 0;
  bool inString = false;
  for (size_t i = 0; i < text.size(); ++i)
  {
    const char c = text[i];
    if (inString)
    {
      if (c == '\\')
        ++i;
      else if (c == '"')
        inString = false;
    }
    else if (c == '"')
      inString = true;
    else if (c == '[' || c == '{')
      deepest = std::max(deepest, ++depth);
    else if (c == ']' || c == '}')
      --depth;
  }
  return deepest;
}

/// The deepest nesting of arrays and objects the JSON inputs accept (material
/// tables, materials, paint/stroke files, scene files need at most 4): deeper
/// input is refused before it is parsed, so that no recursive walk (dumping a
/// value into a message) can overflow the stack.
constexpr int MaxJsonNesting = 64;

/// "(x, y, z)" with 6 significant digits, for error messages naming a point (mm).
inline std::string FormatPoint(const double* x)
{
  std::ostringstream out;
  out.precision(6);
  out << "(" << x[0] << ", " << x[1] << ", " << x[2] << ")";
  return out.str();
}

/// The name of item k (0-based) of a list in messages: its label, or
/// "<kind> <k + 1>" when the label is empty (e.g. "detector 2").
inline std::string NameOf(const std::string& label, const char* kind, std::size_t k)
{
  return label.empty() ? std::string(kind) + " " + std::to_string(k + 1) : label;
}

} // namespace translucency
