#pragma once
// The lockstep protocol's message table (python/hpa_sim/messages.json, compiled into the library):
// its base types, its fields and structs as parsed, and the table itself, resolved once. The
// codec that walks it is wire_codec.h; message_table.h gathers both.

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "hpa/flight/protocol.h"

namespace hpa::flight::wire {

/// How a field crosses the wire (the table's base types).
enum class Kind { kF64, kU32, kI32, kBool, kEnum, kFlags, kText, kStruct };

struct Struct;

/// One bit of a flags field.
struct Bit {
  std::string name;       // its name (the Python client's dict key)
  std::string label;      // as error messages and the choices list name it
  uint32_t value = 0;     // its value in the u32
  uint32_t requires = 0;  // a bit that must be set with it (0: none)
  std::string refused;    // the error when it is set without `requires`
};

/// A unit-quaternion check of a struct-typed field: the norm of its quaternion member `field`
/// must lie in [min_norm, max_norm]; off unit by more than renormalise_beyond, it is renormalised.
struct UnitQuaternion {
  std::string field;
  double min_norm = 0.0, max_norm = 0.0, renormalise_beyond = 0.0;
  std::string refused;
};

/// One field of a struct, as the table declares it.
struct Field {
  std::string name;   // its name (the C++ binding's and the Python client's key)
  std::string label;  // as error messages name it (default: the name)
  std::string unit;   // "s", "m", "-" for a pure number, "" for a flag or text
  Kind kind = Kind::kF64;
  int count = 1;                    // numbers of a vector (f64, i32)
  bool list = false;                // a u32 count, then that many items
  std::string item;                 // a list's item as error messages name it ("detection")
  const Struct* type = nullptr;     // kStruct: the struct it holds
  std::vector<std::string> values;  // kEnum: the names of 0, 1, ...
  std::vector<Bit> bits;            // kFlags
  uint32_t gate = 0;    // the bit of its struct's flags field that says it is present (0: always)
  bool finite = false;  // every number in it is finite
  std::optional<double> min, max;  // each number's range
  std::string refused;             // the error when a check fails ({label}, {value}, {min}, ...)
  std::optional<UnitQuaternion> unit_quaternion;
  size_t min_bytes = 0;  // its smallest encoding (a list: its count)
};

/// A struct of the table: its fields in wire order.
struct Struct {
  std::string name;
  std::vector<Field> fields;
  size_t min_bytes = 0;  // its smallest encoding
};

/// Named values for an error template's {name} placeholders.
using Vars = std::vector<std::pair<std::string, std::string>>;

/// `text` with each {name} of `vars` replaced by its value.
std::string Format(std::string text, const Vars& vars);
/// A number as an error message shows it: every digit that tells it apart (%.17g).
std::string ShownValue(double v);
/// A declared limit as an error message shows it (%.15g: as it was written).
std::string ShownLimit(double v);
/// An error prefix naming where a field is ("truth " for a field of tick.truth, "" at the top).
std::string In(const std::string& at);
/// The possessive form of In ("detection 0's ").
std::string Of(const std::string& at);

/// The message table, parsed and resolved once.
class Table {
 public:
  /// The compiled-in table; throws std::logic_error if it is inconsistent (an unknown type, a
  /// gate naming no earlier bit, a check without its refusal text, a framing constant that
  /// differs from protocol.h's).
  static const Table& Get();
  /// The struct named `name`; std::logic_error if the table has none.
  const Struct& Find(const std::string& name) const;
  /// The error template `key` of the table's "errors", filled with `vars`.
  std::string Error(const std::string& key, const Vars& vars) const;
  /// The table as JSON.
  const nlohmann::json& json() const { return json_; }

 private:
  Table();
  const Struct& Resolve(const std::string& name);
  Field ParseField(const nlohmann::json& j, const std::string& where);
  // Checks a JSON message's key declarations (each named once, a known type, a doc).
  void CheckKeyDeclarations(const nlohmann::json& keys, const std::string& where);
  nlohmann::json json_;
  std::map<std::string, Struct> structs_;  // by name (std::map: stable addresses)
  std::map<std::string, bool> resolving_;
};

}  // namespace hpa::flight::wire
