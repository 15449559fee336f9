/**
 * @file SolverOptions.h
 * @brief Settings that only some members of a family read, by name (model:
 * PETSc's options database and KSPSetFromOptions_<type>). A caller that only
 * holds the interface fills one SolverOptions; each concrete object reads
 * the names it knows (`Read*`), which marks them used; the caller may then
 * ask which were left unused (PETSc's -options_left) to report them.
 *
 * Names are case-insensitive (stored lower case). Values are numbers; a
 * flag is 0 (off) or 1 (on), a count an integer.
 */
#pragma once

#include "Error.h"
#include "Strings.h"

#include <cmath>
#include <initializer_list>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace translucency
{

class SolverOptions
{
public:
  SolverOptions() = default;
  /// E.g. `SolverOptions{ { "grid-spacing", 0.2 }, { "multilevel", 1 } }`.
  SolverOptions(std::initializer_list<std::pair<std::string, double>> values)
  {
    for (const auto& value : values)
    {
      Set(value.first, value.second);
    }
  }

  /// Sets (or replaces) the option `name`; returns *this to chain.
  SolverOptions& Set(const std::string& name, double value)
  {
    Values_[ToLower(name)] = value;
    return *this;
  }

  /// Whether `name` is set.
  bool Has(const std::string& name) const { return Values_.count(ToLower(name)) != 0; }

  /// Every option, by name (sorted).
  const std::map<std::string, double>& GetValues() const { return Values_; }

  ///@{
  /**
   * Readers for the concrete objects: if `name` is set, mark it used, check
   * its value and store it in `value` (returns true); otherwise leave
   * `value` unchanged (returns false). An invalid value throws
   * translucency::Error "<who>: option <name> = <value> is invalid: <rule>"
   * and leaves `value` unchanged.
   */
  /// Any finite number >= `minimum` (`rule` says what it means, e.g. "the
  /// voxel spacing in mm must be > 0, or 0 for automatic").
  bool ReadNumber(const std::string& who, const std::string& name, double minimum,
    const std::string& rule, double& value) const
  {
    double v = 0.0;
    if (!Take(name, v))
    {
      return false;
    }
    if (!std::isfinite(v) || v < minimum)
    {
      Refuse(who, name, v, rule);
    }
    value = v;
    return true;
  }
  /// An integer >= `minimum` (and <= 2^53, exact in a double).
  template <typename Integer>
  bool ReadInteger(const std::string& who, const std::string& name, double minimum,
    const std::string& rule, Integer& value) const
  {
    double v = 0.0;
    if (!Take(name, v))
    {
      return false;
    }
    if (!std::isfinite(v) || v < minimum || v > 9007199254740992.0 || v != std::floor(v))
    {
      Refuse(who, name, v, rule);
    }
    value = static_cast<Integer>(v);
    return true;
  }
  /// 0 (off) or 1 (on).
  bool ReadFlag(const std::string& who, const std::string& name, bool& value) const
  {
    double v = 0.0;
    if (!Take(name, v))
    {
      return false;
    }
    if (v != 0.0 && v != 1.0)
    {
      Refuse(who, name, v, "it is a flag: 0 (off) or 1 (on)");
    }
    value = v != 0.0;
    return true;
  }
  ///@}

  /// Names no reader has taken yet (sorted), e.g. to report options that do
  /// not apply to the object they were given to.
  std::vector<std::string> GetUnused() const
  {
    std::vector<std::string> unused;
    for (const auto& value : Values_)
    {
      if (!Used_.count(value.first))
      {
        unused.push_back(value.first);
      }
    }
    return unused;
  }

  /// Forget which options were read (to give the same options to another object).
  void ClearUsed() const { Used_.clear(); }

private:
  bool Take(const std::string& name, double& value) const
  {
    const auto it = Values_.find(ToLower(name));
    if (it == Values_.end())
    {
      return false;
    }
    Used_.insert(it->first);
    value = it->second;
    return true;
  }

  [[noreturn]] static void Refuse(
    const std::string& who, const std::string& name, double value, const std::string& rule)
  {
    std::ostringstream os;
    os.precision(15); // -0.1 reads -0.1; enough digits to see 1.0000001
    os << who << ": option " << ToLower(name) << " = " << value << " is invalid: " << rule;
    throw Error(os.str());
  }

  std::map<std::string, double> Values_;
  /// Reading is not a change of the options (a const reference is handed
  /// to each reader), hence mutable, as PETSc's "used" marks.
  mutable std::set<std::string> Used_;
};

} // namespace translucency
