/**
 * @file Error.h
 * @brief The exception type of the numerical core.
 *
 * Every check that guards user input in Solvers/ is always on (not only in
 * debug builds) and throws translucency::Error with a message a user can act
 * on: which element, which value, what was expected.
 */
#pragma once

#include <stdexcept>
#include <string>

namespace translucency
{

/// Error raised by the numerical core. The message names the problem.
class Error : public std::runtime_error
{
public:
  explicit Error(const std::string& what)
    : std::runtime_error(what)
  {
  }
};

} // namespace translucency
