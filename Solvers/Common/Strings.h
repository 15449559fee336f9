/**
 * @file Strings.h
 * @brief The string helpers every layer shares: case folding of the names
 * users type (solvers, presets, options) and the lists of known names that
 * error messages and help texts show.
 */
#pragma once

#include <algorithm>
#include <cctype>
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

} // namespace translucency
