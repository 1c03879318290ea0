#pragma once
// The one registry template behind every named, extensible list: controllers, estimators, OCP
// solvers, event types, expect keys, reference types and metrics. An entry is a struct with a
// `name`; entries keep their registration order (built-ins first), and adding one checks the
// name is new and, where the entry has a factory (`make`) or a reader, that it is set.

#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace hpa {

/// An ordered list of named entries of type Entry (a struct with `std::string name`, or `key`
/// where the name is a YAML key).
template <typename Entry>
class Registry {
 public:
  /// A registry of `kind` (e.g. "controller", for messages) holding the built-in entries.
  Registry(std::string kind, std::vector<Entry> built_ins) : kind_(std::move(kind)) {
    for (Entry& entry : built_ins) Add(std::move(entry));
  }

  /// Every entry, in registration order.
  const std::vector<Entry>& All() const { return entries_; }

  /// The entry called `name`, or nullptr; valid until the next Add.
  const Entry* Find(const std::string& name) const {
    for (const Entry& entry : entries_) {
      if (NameOf(entry) == name) return &entry;
    }
    return nullptr;
  }

  /// The entry called `name`; throws std::invalid_argument naming `what` and the known names.
  const Entry& Get(const std::string& name, const std::string& what) const {
    const Entry* entry = Find(name);
    if (entry == nullptr) {
      throw std::invalid_argument(what + ": expected one of " + JoinedNames() + ", got '" + name +
                                  "'");
    }
    return *entry;
  }

  /// The names of every entry, in registration order.
  std::vector<std::string> Names() const {
    std::vector<std::string> names;
    for (const Entry& entry : entries_) names.push_back(NameOf(entry));
    return names;
  }

  /// The names joined by `separator` ("a, b, c"), for messages and --help.
  std::string JoinedNames(const std::string& separator = ", ") const {
    std::string joined;
    for (const Entry& entry : entries_) joined += (joined.empty() ? "" : separator) + NameOf(entry);
    return joined;
  }

  /// Adds an entry; throws std::invalid_argument on an empty or duplicate name or an unset
  /// factory.
  void Add(Entry entry) {
    const std::string name = NameOf(entry);
    if (name.empty()) throw std::invalid_argument("register " + kind_ + ": empty name");
    if constexpr (HasMake<Entry>::value) {
      if (!entry.make) {
        throw std::invalid_argument("register " + kind_ + ": '" + name + "' has no factory");
      }
    }
    if (Find(name) != nullptr) {
      throw std::invalid_argument("register " + kind_ + ": '" + name + "' is already registered");
    }
    entries_.push_back(std::move(entry));
  }

 private:
  template <typename T, typename = void>
  struct HasName : std::false_type {};
  template <typename T>
  struct HasName<T, std::void_t<decltype(std::declval<T&>().name)>> : std::true_type {};
  template <typename T, typename = void>
  struct HasMake : std::false_type {};
  template <typename T>
  struct HasMake<T, std::void_t<decltype(std::declval<T&>().make)>> : std::true_type {};

  static const std::string& NameOf(const Entry& entry) {
    if constexpr (HasName<Entry>::value) {
      return entry.name;
    } else {
      return entry.key;
    }
  }

  std::string kind_;
  std::vector<Entry> entries_;
};

}  // namespace hpa
