#pragma once
// The codec that walks the message table: each C++ struct that crosses the wire binds its members
// to its table struct's fields by name once (a Codec built from wire_bindings.h's Bind and
// BindBit); encoding and decoding then walk the table's fields in their declared order, applying
// each field's declared checks.

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdint>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "wire_bytes.h"
#include "wire_table.h"

namespace hpa::flight::wire {

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

}  // namespace hpa::flight::wire
