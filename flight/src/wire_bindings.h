#pragma once
// The bindings a Codec is built from: Bind ties a field of the message table to a member of a
// C++ struct (a plain value, a struct coded by its own codec, gated by a bool or held in a
// std::optional, or a list), BindBit ties a flag bit to a bool; a struct-typed field's own
// checks (finite, unit quaternion) run on its decoded value.

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "wire_bytes.h"
#include "wire_codec.h"
#include "wire_table.h"
#include "wire_value_slots.h"

namespace hpa::flight::wire {
namespace detail {

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
