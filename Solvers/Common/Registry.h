/**
 * @file Registry.h
 * @brief One table per pluggable family (diffusion solvers, linear solvers,
 * later light sources): a name, a factory, traits and one line of help per
 * entry. The table feeds the factory, the VTK filters' SetXByName, the CLI
 * help and the test that compares it with the plugin XML's enumeration, so
 * a new entry is written once (model: PETSc's KSPRegisterAll).
 *
 * An interface sits below its implementations, the registry above them:
 * Registry<Base> only needs Base declared; the layer that knows every
 * implementation fills the table.
 */
#pragma once

#include "Error.h"
#include "Strings.h"

#include <algorithm>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace translucency
{

/**
 * The entries of one family, in the order they are listed (the first one is
 * the default). `Traits` is a plain struct of the family's own (e.g. "needs
 * a symmetric matrix"); use an empty struct when there is none.
 */
template <typename Base, typename Traits>
class Registry
{
public:
  struct Entry
  {
    std::string Name;                              ///< lower case, what users type
    std::function<std::unique_ptr<Base>()> Create; ///< a new instance
    Traits Properties;                             ///< the family's traits
    std::string Help;                              ///< one line for --help and docs
  };

  /// `family` names the family in error messages ("solver", "linear solver").
  explicit Registry(std::string family)
    : Family_(std::move(family))
  {
  }

  /// Adds an entry; throws if the name is taken (a programming error).
  void Add(Entry entry)
  {
    entry.Name = ToLower(entry.Name);
    if (Find(entry.Name))
    {
      throw Error(Family_ + " '" + entry.Name + "' is registered twice");
    }
    Entries_.push_back(std::move(entry));
  }

  /// Every entry, in listing order.
  const std::vector<Entry>& GetEntries() const { return Entries_; }

  /// Names in listing order.
  std::vector<std::string> GetNames() const
  {
    std::vector<std::string> names;
    for (const Entry& entry : Entries_)
    {
      names.push_back(entry.Name);
    }
    return names;
  }

  /// The entry called `name` (case-insensitive), or null.
  const Entry* Find(const std::string& name) const
  {
    const std::string key = ToLower(name);
    for (const Entry& entry : Entries_)
    {
      if (entry.Name == key)
      {
        return &entry;
      }
    }
    return nullptr;
  }

  /// The entry called `name`; throws translucency::Error naming the family,
  /// the unknown name and the known ones.
  const Entry& Get(const std::string& name) const
  {
    if (const Entry* entry = Find(name))
    {
      return *entry;
    }
    throw Error("unknown " + Family_ + " '" + name + "' (known " + Family_ + "s: " +
      JoinNames(GetNames()) + ")");
  }

  /// A new instance of `name`; throws as Get().
  std::unique_ptr<Base> Create(const std::string& name) const { return Get(name).Create(); }

  /// "  name    help" lines for a help text, names padded to one column.
  std::string FormatHelp(const std::string& indent = "  ") const
  {
    std::size_t width = 0;
    for (const Entry& entry : Entries_)
    {
      width = std::max(width, entry.Name.size());
    }
    std::string text;
    for (const Entry& entry : Entries_)
    {
      text += indent + entry.Name + std::string(width + 2 - entry.Name.size(), ' ') + entry.Help +
        "\n";
    }
    return text;
  }

private:
  std::string Family_;
  std::vector<Entry> Entries_;
};

} // namespace translucency
