#pragma once
// The lockstep protocol's message table (python/hpa_sim/messages.json, compiled into the library)
// and the generic codec that walks it. Each C++ struct that crosses the wire binds its members
// to the table's fields by name once (a Codec built from Bind and BindBit); encoding and decoding
// walk the table's fields in their declared order, applying each field's declared checks, so a
// field's name, type, unit, range and refusal text live in the table alone. The Python client
// (hpa_sim/lockstep.py) walks the same file.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
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

/// Appends little-endian numbers (this machine's order: x86-64 and arm64 are little-endian).
class Writer {
 public:
  /// Appends one f64.
  void F64(double v) { Raw(&v, 8); }
  /// Appends one u32.
  void U32(uint32_t v) { Raw(&v, 4); }
  /// Appends a u32 byte count and the bytes.
  void Text(const std::string& s);
  std::vector<uint8_t> bytes;  // what was written

 private:
  void Raw(const void* p, size_t n);
};

/// Reads what Writer wrote; every read is bounds-checked, every refusal names the message.
class Reader {
 public:
  /// Reads `bytes`, a body of the message `message` ("tick", "finish", "tick_reply").
  Reader(const std::vector<uint8_t>& bytes, std::string message)
      : bytes_(bytes), message_(std::move(message)) {}
  /// Reads one f64.
  double F64();
  /// Reads one u32.
  uint32_t U32();
  /// Reads a text field: its byte count, then UTF-8; refused when longer than the message or
  /// not UTF-8.
  std::string Text(const Field& f, const std::string& at);
  /// Reads a list's count; refused when the message cannot hold that many items.
  uint32_t Count(const Field& f);
  /// Refuses bytes after the message's end.
  void End();
  /// Throws ProtocolError "malformed MESSAGE message: WHAT".
  [[noreturn]] void Fail(const std::string& what) const;

 private:
  void Raw(void* p, size_t n);
  const std::vector<uint8_t>& bytes_;
  std::string message_;
  size_t pos_ = 0;
};

/// Refuses `v` (a number of field `f` at `at`) outside the field's declared checks.
void CheckNumber(const Reader& r, const Field& f, const std::string& at, double v);
/// Refuses a flags value with unknown bits or a bit without the bit it requires.
void CheckFlags(const Reader& r, const Field& f, const std::string& at, uint32_t flags);

/// One table field bound to a member of T: how it is written, read and checked.
template <class T>
struct Slot {
  const Field* field = nullptr;
  std::function<void(const T&, Writer&)> put;
  std::function<void(Reader&, T&, const std::string& at)> get;
  std::function<bool(const T&)> present;              // a gated field: whether it is there
  std::function<bool(const T&)> all_finite;           // every number in it is finite
  std::function<Eigen::Quaterniond*(T&)> quaternion;  // a quaternion member, else null
};

/// One bit of a flags field bound to a boolean of T.
template <class T>
struct BitSlot {
  uint32_t value = 0;
  std::function<bool(const T&)> get;
  std::function<void(T&, bool)> set;
};

/// A binding of one table name (a field or a bit) to T, resolved against the table by Codec.
template <class T>
struct Binding {
  std::string name;
  std::function<Slot<T>(const Field&)> make;  // a field's binding
  std::function<bool(const T&)> bit_get;      // a bit's binding
  std::function<void(T&, bool)> bit_set;
};

/// The codec of one C++ struct bound to one struct of the table.
template <class T>
class Codec {
 public:
  /// Binds `bindings` to the table's struct `name`; throws std::logic_error naming a field or
  /// bit of the table that no binding covers, a binding the table does not declare, or a member
  /// whose C++ type does not fit the field's type.
  Codec(const std::string& name, const std::vector<Binding<T>>& bindings)
      : spec_(&Table::Get().Find(name)) {
    std::map<std::string, const Binding<T>*> by_name;
    for (const Binding<T>& b : bindings) {
      if (!by_name.emplace(b.name, &b).second) Mismatch(b.name, "is bound twice");
    }
    const auto take = [&](const std::string& key) -> const Binding<T>* {
      const auto it = by_name.find(key);
      if (it == by_name.end()) return nullptr;
      const Binding<T>* b = it->second;
      by_name.erase(it);
      return b;
    };
    for (const Field& f : spec_->fields) {
      if (f.kind == Kind::kFlags) {
        Slot<T> slot;
        slot.field = &f;
        slots_.push_back(slot);
        for (const Bit& bit : f.bits) {
          const bool gates = std::any_of(spec_->fields.begin(), spec_->fields.end(),
                                         [&](const Field& g) { return g.gate == bit.value; });
          const Binding<T>* b = take(bit.name);
          if (gates) {
            if (b != nullptr) Mismatch(bit.name, "gates a field: its field's binding sets it");
            continue;
          }
          if (b == nullptr || !b->bit_get) Mismatch(bit.name, "is not bound to a C++ bool");
          bits_.push_back({bit.value, b->bit_get, b->bit_set});
        }
        continue;
      }
      const Binding<T>* b = take(f.name);
      if (b == nullptr || !b->make) Mismatch(f.name, "is not bound to a C++ member");
      slots_.push_back(b->make(f));
      if (f.gate != 0 && !slots_.back().present)
        Mismatch(f.name, "is gated but bound as always there");
    }
    if (!by_name.empty()) Mismatch(by_name.begin()->first, "is bound but not in the table");
  }

  /// Writes `obj` field by field, its flags from its bits and its gated fields' presence.
  void Encode(const T& obj, Writer& w) const {
    uint32_t flags = 0;
    for (const Slot<T>& s : slots_) {
      const Field& f = *s.field;
      if (f.kind == Kind::kFlags) {
        for (const BitSlot<T>& b : bits_) flags |= b.get(obj) ? b.value : 0u;
        for (const Slot<T>& g : slots_) flags |= g.present && g.present(obj) ? g.field->gate : 0u;
        w.U32(flags);
      } else if (f.gate == 0 || (flags & f.gate) != 0) {
        s.put(obj, w);
      }
    }
  }

  /// Reads `obj` field by field, each checked as declared; `at` names it in errors.
  void Decode(Reader& r, T& obj, const std::string& at) const {
    uint32_t flags = 0;
    for (const Slot<T>& s : slots_) {
      const Field& f = *s.field;
      if (f.kind == Kind::kFlags) {
        flags = r.U32();
        CheckFlags(r, f, at, flags);
      } else if (f.gate == 0 || (flags & f.gate) != 0) {
        s.get(r, obj, at);
      }
    }
    // after the gated fields, so a bit may be stored inside one of them
    for (const BitSlot<T>& b : bits_) b.set(obj, (flags & b.value) != 0);
  }

  /// Whether every number of `obj` is finite.
  bool AllFinite(const T& obj) const {
    for (const Slot<T>& s : slots_) {
      if (s.all_finite && !s.all_finite(obj)) return false;
    }
    return true;
  }

  /// The quaternion member bound to the field `name` of `obj` (std::logic_error if none).
  Eigen::Quaterniond* Quaternion(T& obj, const std::string& name) const {
    for (const Slot<T>& s : slots_) {
      if (s.field->name == name && s.quaternion) return s.quaternion(obj);
    }
    Mismatch(name, "is not bound to a quaternion");
  }

  /// The table's struct.
  const Struct& spec() const { return *spec_; }

 private:
  [[noreturn]] void Mismatch(const std::string& name, const std::string& what) const {
    throw std::logic_error("messages.json's " + spec_->name + "." + name + " " + what);
  }
  const Struct* spec_;
  std::vector<Slot<T>> slots_;
  std::vector<BitSlot<T>> bits_;
};

namespace detail {

template <class>
inline constexpr bool kAlwaysFalse = false;

template <class M>
struct IsColumn : std::false_type {};
template <int N>
struct IsColumn<Eigen::Matrix<double, N, 1>> : std::true_type {};

[[noreturn]] void WrongType(const Field& f, const char* cpp);

// Refuses a field of the table whose declared shape does not fit the C++ member.
inline void Expect(const Field& f, bool fits, const char* cpp) {
  if (!fits || f.list || f.gate != 0) WrongType(f, cpp);
}

// The slot of a numeric, text or enum member.
template <class T, class M>
Slot<T> ValueSlot(const Field& f, M T::*m) {
  Slot<T> s;
  s.field = &f;
  s.all_finite = [](const T&) { return true; };
  if constexpr (std::is_same_v<M, double>) {
    Expect(f, f.kind == Kind::kF64 && f.count == 1, "double");
    s.put = [m](const T& o, Writer& w) { w.F64(o.*m); };
    s.get = [m, &f](Reader& r, T& o, const std::string& at) {
      o.*m = r.F64();
      CheckNumber(r, f, at, o.*m);
    };
    s.all_finite = [m](const T& o) { return std::isfinite(o.*m); };
  } else if constexpr (IsColumn<M>::value) {
    Expect(f, f.kind == Kind::kF64 && f.count == M::RowsAtCompileTime, "an Eigen vector");
    s.put = [m](const T& o, Writer& w) {
      for (int i = 0; i < M::RowsAtCompileTime; ++i) w.F64((o.*m)[i]);
    };
    s.get = [m, &f](Reader& r, T& o, const std::string& at) {
      for (int i = 0; i < M::RowsAtCompileTime; ++i) {
        (o.*m)[i] = r.F64();
        CheckNumber(r, f, at, (o.*m)[i]);
      }
    };
    s.all_finite = [m](const T& o) { return (o.*m).allFinite(); };
  } else if constexpr (std::is_same_v<M, Eigen::Quaterniond>) {
    // w, x, y, z on the wire
    Expect(f, f.kind == Kind::kF64 && f.count == 4, "a quaternion");
    s.put = [m](const T& o, Writer& w) {
      const Eigen::Quaterniond& q = o.*m;
      w.F64(q.w()), w.F64(q.x()), w.F64(q.y()), w.F64(q.z());
    };
    s.get = [m, &f](Reader& r, T& o, const std::string& at) {
      double v[4];
      for (double& x : v) {
        x = r.F64();
        CheckNumber(r, f, at, x);
      }
      o.*m = Eigen::Quaterniond(v[0], v[1], v[2], v[3]);
    };
    s.all_finite = [m](const T& o) { return (o.*m).coeffs().allFinite(); };
    s.quaternion = [m](T& o) { return &(o.*m); };
  } else if constexpr (std::is_same_v<M, cv::Rect>) {
    // x, y, width, height
    Expect(f, f.kind == Kind::kI32 && f.count == 4, "a cv::Rect");
    s.put = [m](const T& o, Writer& w) {
      const cv::Rect& rect = o.*m;
      for (const int v : {rect.x, rect.y, rect.width, rect.height}) w.U32(static_cast<uint32_t>(v));
    };
    s.get = [m](Reader& r, T& o, const std::string&) {
      int v[4];
      for (int& x : v) x = static_cast<int32_t>(r.U32());
      o.*m = cv::Rect(v[0], v[1], v[2], v[3]);
    };
  } else if constexpr (std::is_same_v<M, int>) {
    // an i32, or a u32 whose declared range fits an int
    const bool fits_int =
        f.kind == Kind::kU32 && f.max.has_value() && *f.max <= std::numeric_limits<int32_t>::max();
    Expect(f, f.count == 1 && (f.kind == Kind::kI32 || fits_int), "an int");
    s.put = [m](const T& o, Writer& w) { w.U32(static_cast<uint32_t>(o.*m)); };
    if (f.kind == Kind::kI32) {
      s.get = [m](Reader& r, T& o, const std::string&) { o.*m = static_cast<int32_t>(r.U32()); };
    } else {
      s.get = [m, &f](Reader& r, T& o, const std::string& at) {
        const uint32_t v = r.U32();
        CheckNumber(r, f, at, v);
        o.*m = static_cast<int>(v);
      };
    }
  } else if constexpr (std::is_same_v<M, bool>) {
    Expect(f, f.kind == Kind::kBool, "a bool");
    s.put = [m](const T& o, Writer& w) { w.U32(o.*m ? 1u : 0u); };
    s.get = [m, &f](Reader& r, T& o, const std::string& at) {
      const uint32_t v = r.U32();
      if (v > 1) {
        r.Fail(Table::Get().Error(
            "bool", {{"in", In(at)}, {"label", f.label}, {"value", std::to_string(v)}}));
      }
      o.*m = v == 1;
    };
  } else if constexpr (std::is_same_v<M, std::string>) {
    Expect(f, f.kind == Kind::kText, "a std::string");
    s.put = [m](const T& o, Writer& w) { w.Text(o.*m); };
    s.get = [m, &f](Reader& r, T& o, const std::string& at) { o.*m = r.Text(f, at); };
  } else if constexpr (std::is_enum_v<M>) {
    // the table's values are the enum's, in order, as its ToString names them
    Expect(f, f.kind == Kind::kEnum, "an enum");
    for (size_t i = 0; i < f.values.size(); ++i) {
      if (f.values[i] != ToString(static_cast<M>(i))) WrongType(f, "an enum of other names");
    }
    s.put = [m](const T& o, Writer& w) { w.U32(static_cast<uint32_t>(o.*m)); };
    s.get = [m, &f](Reader& r, T& o, const std::string& at) {
      const uint32_t v = r.U32();
      if (v >= f.values.size()) {
        std::string choices;
        for (size_t i = 0; i < f.values.size(); ++i) {
          choices += (i == 0                     ? ""
                      : i + 1 == f.values.size() ? " or "
                                                 : ", ") +
                     std::to_string(i) + " " + f.values[i];
        }
        r.Fail(Table::Get().Error("enum", {{"in", In(at)},
                                           {"label", f.label},
                                           {"value", std::to_string(v)},
                                           {"choices", choices}}));
      }
      o.*m = static_cast<M>(v);
    };
  } else {
    static_assert(kAlwaysFalse<M>, "a member type the protocol does not carry");
  }
  return s;
}

// Applies a struct-typed field's own checks (finite, unit quaternion) to its decoded value.
template <class U>
void CheckStruct(const Reader& r, const Field& f, const Codec<U>& codec, U& v) {
  if (f.finite && !codec.AllFinite(v)) r.Fail(f.refused);
  if (f.unit_quaternion) {
    const UnitQuaternion& uq = *f.unit_quaternion;
    Eigen::Quaterniond* q = codec.Quaternion(v, uq.field);
    const double norm = q->norm();
    if (!(norm >= uq.min_norm && norm <= uq.max_norm)) {
      r.Fail(Format(uq.refused, {{"value", ShownValue(norm)},
                                 {"min", ShownLimit(uq.min_norm)},
                                 {"max", ShownLimit(uq.max_norm)}}));
    }
    // an attitude off unit by more than rounding is renormalised; a unit one keeps every bit
    if (std::fabs(norm - 1.0) > uq.renormalise_beyond) q->normalize();
  }
}

}  // namespace detail

/// Binds the table's field `name` to the member `m` (a number, vector, quaternion, cv::Rect,
/// int, bool, string or enum).
template <class T, class M>
Binding<T> Bind(const std::string& name, M T::*m) {
  return {name, [m](const Field& f) { return detail::ValueSlot<T, M>(f, m); }, {}, {}};
}

/// Binds the table's struct-typed field `name` to the member `m`, coded by `codec`.
template <class T, class U>
Binding<T> Bind(const std::string& name, U T::*m, const Codec<U>& codec) {
  return {name,
          [m, &codec](const Field& f) {
            detail::Expect(f, f.kind == Kind::kStruct && f.type == &codec.spec(), "its struct");
            Slot<T> s;
            s.field = &f;
            s.put = [m, &codec](const T& o, Writer& w) { codec.Encode(o.*m, w); };
            s.get = [m, &codec, &f](Reader& r, T& o, const std::string&) {
              codec.Decode(r, o.*m, f.name);
              detail::CheckStruct(r, f, codec, o.*m);
            };
            s.all_finite = [m, &codec](const T& o) { return codec.AllFinite(o.*m); };
            return s;
          },
          {},
          {}};
}

/// Binds the table's gated struct-typed field `name` to the member `m`, there when the bool
/// member `has` is true.
template <class T, class U>
Binding<T> Bind(const std::string& name, U T::*m, const Codec<U>& codec, bool T::*has) {
  return {name,
          [m, &codec, has](const Field& f) {
            if (f.kind != Kind::kStruct || f.type != &codec.spec() || f.list || f.gate == 0) {
              detail::WrongType(f, "a gated struct");
            }
            Slot<T> s;
            s.field = &f;
            s.put = [m, &codec](const T& o, Writer& w) { codec.Encode(o.*m, w); };
            s.get = [m, &codec, has, &f](Reader& r, T& o, const std::string&) {
              o.*has = true;
              codec.Decode(r, o.*m, f.name);
              detail::CheckStruct(r, f, codec, o.*m);
            };
            s.present = [has](const T& o) { return o.*has; };
            s.all_finite = [m, has, &codec](const T& o) {
              return !(o.*has) || codec.AllFinite(o.*m);
            };
            return s;
          },
          {},
          {}};
}

/// Binds the table's gated struct-typed field `name` to the optional member `m`.
template <class T, class U>
Binding<T> Bind(const std::string& name, std::optional<U> T::*m, const Codec<U>& codec) {
  return {name,
          [m, &codec](const Field& f) {
            if (f.kind != Kind::kStruct || f.type != &codec.spec() || f.list || f.gate == 0) {
              detail::WrongType(f, "a std::optional");
            }
            Slot<T> s;
            s.field = &f;
            s.put = [m, &codec](const T& o, Writer& w) { codec.Encode(*(o.*m), w); };
            s.get = [m, &codec, &f](Reader& r, T& o, const std::string&) {
              U& v = (o.*m).emplace();
              codec.Decode(r, v, f.name);
              detail::CheckStruct(r, f, codec, v);
            };
            s.present = [m](const T& o) { return (o.*m).has_value(); };
            s.all_finite = [m, &codec](const T& o) { return !(o.*m) || codec.AllFinite(*(o.*m)); };
            return s;
          },
          {},
          {}};
}

/// Binds the table's list field `name` to the vector member `m`, each item coded by `codec`.
template <class T, class U>
Binding<T> Bind(const std::string& name, std::vector<U> T::*m, const Codec<U>& codec) {
  return {name,
          [m, &codec](const Field& f) {
            if (f.kind != Kind::kStruct || f.type != &codec.spec() || !f.list || f.gate != 0) {
              detail::WrongType(f, "a std::vector");
            }
            Slot<T> s;
            s.field = &f;
            s.put = [m, &codec](const T& o, Writer& w) {
              w.U32(static_cast<uint32_t>((o.*m).size()));
              for (const U& v : o.*m) codec.Encode(v, w);
            };
            s.get = [m, &codec, &f](Reader& r, T& o, const std::string&) {
              std::vector<U>& items = o.*m;
              items.resize(r.Count(f));
              for (size_t i = 0; i < items.size(); ++i) {
                codec.Decode(r, items[i], f.item + " " + std::to_string(i));
              }
            };
            s.all_finite = [m, &codec](const T& o) {
              for (const U& v : o.*m) {
                if (!codec.AllFinite(v)) return false;
              }
              return true;
            };
            return s;
          },
          {},
          {}};
}

/// Binds the table's flag bit `name` to the bool member `m`.
template <class T>
Binding<T> BindBit(const std::string& name, bool T::*m) {
  return {name, {}, [m](const T& o) { return o.*m; }, [m](T& o, bool v) { o.*m = v; }};
}

/// Binds the table's flag bit `name` to a bool reached through `get` and `set` (set runs after
/// the struct's other fields are read).
template <class T>
Binding<T> BindBit(const std::string& name, std::function<bool(const T&)> get,
                   std::function<void(T&, bool)> set) {
  return {name, {}, std::move(get), std::move(set)};
}

}  // namespace hpa::flight::wire
