/**
 * @file   vtkTranslucencyNumbers.h
 * @brief  Whole-token number parsing for the readers (std::from_chars:
 *         independent of the C locale, no allocation). Private to Readers/.
 */
#ifndef vtkTranslucencyNumbers_h
#define vtkTranslucencyNumbers_h

#include <charconv>
#include <string_view>
#include <system_error>

namespace vtkTranslucencyNumbers
{
/// The token without one leading '+' (std::from_chars takes none), unless
/// the '+' is all there is or a '-' follows it (then unchanged: not a number).
inline std::string_view StripPlus(std::string_view token)
{
  if (token.size() > 1 && token[0] == '+' && token[1] != '-')
  {
    token.remove_prefix(1);
  }
  return token;
}

/// The whole token as a number of type T (an optional leading '+'); false if
/// it is empty, not a number, out of T's range or followed by anything.
template <class T>
bool ParseWhole(std::string_view token, T& value)
{
  token = StripPlus(token);
  const char* first = token.data();
  const char* last = first + token.size();
  const std::from_chars_result result = std::from_chars(first, last, value);
  return first != last && result.ec == std::errc() && result.ptr == last;
}
}

#endif
