#pragma once
// How a member of a plain type crosses the wire: the slot (write, read and check) of a double,
// an Eigen vector, a quaternion, a cv::Rect, an int, a bool, a string or an enum member bound to
// a field of the message table, each refusing a field whose declared shape does not fit it.
// wire_bindings.h's Bind builds them.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <opencv2/core.hpp>
#include <string>
#include <type_traits>

#include "wire_bytes.h"
#include "wire_codec.h"
#include "wire_table.h"

namespace hpa::flight::wire::detail {

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

// Fills the slot `s` of a double member: one f64.
template <class T>
void DoubleSlot(const Field& f, double T::*m, Slot<T>& s) {
  Expect(f, f.kind == Kind::kF64 && f.count == 1, "double");
  s.put = [m](const T& o, Writer& w) { w.F64(o.*m); };
  s.get = [m, &f](Reader& r, T& o, const std::string& at) {
    o.*m = r.F64();
    CheckNumber(r, f, at, o.*m);
  };
  s.all_finite = [m](const T& o) { return std::isfinite(o.*m); };
}

// Fills the slot `s` of an Eigen column-vector member: its f64s in order.
template <class T, class M>
void ColumnSlot(const Field& f, M T::*m, Slot<T>& s) {
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
}

// Fills the slot `s` of a quaternion member: w, x, y, z on the wire.
template <class T>
void QuaternionSlot(const Field& f, Eigen::Quaterniond T::*m, Slot<T>& s) {
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
}

// Fills the slot `s` of a cv::Rect member: x, y, width, height.
template <class T>
void RectSlot(const Field& f, cv::Rect T::*m, Slot<T>& s) {
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
}

// Fills the slot `s` of an int member: an i32, or a u32 whose declared range fits an int.
template <class T>
void IntSlot(const Field& f, int T::*m, Slot<T>& s) {
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
}

// Fills the slot `s` of a bool member: a u32 of 0 or 1.
template <class T>
void BoolSlot(const Field& f, bool T::*m, Slot<T>& s) {
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
}

// Fills the slot `s` of a std::string member: a text field.
template <class T>
void TextSlot(const Field& f, std::string T::*m, Slot<T>& s) {
  Expect(f, f.kind == Kind::kText, "a std::string");
  s.put = [m](const T& o, Writer& w) { w.Text(o.*m); };
  s.get = [m, &f](Reader& r, T& o, const std::string& at) { o.*m = r.Text(f, at); };
}

// Fills the slot `s` of an enum member: a u32 index into the field's values, which are the
// enum's, in order, as its ToString names them.
template <class T, class M>
void EnumSlot(const Field& f, M T::*m, Slot<T>& s) {
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
}

// The slot of a numeric, text or enum member.
template <class T, class M>
Slot<T> ValueSlot(const Field& f, M T::*m) {
  Slot<T> s;
  s.field = &f;
  s.all_finite = [](const T&) { return true; };
  if constexpr (std::is_same_v<M, double>) {
    DoubleSlot(f, m, s);
  } else if constexpr (IsColumn<M>::value) {
    ColumnSlot(f, m, s);
  } else if constexpr (std::is_same_v<M, Eigen::Quaterniond>) {
    QuaternionSlot(f, m, s);
  } else if constexpr (std::is_same_v<M, cv::Rect>) {
    RectSlot(f, m, s);
  } else if constexpr (std::is_same_v<M, int>) {
    IntSlot(f, m, s);
  } else if constexpr (std::is_same_v<M, bool>) {
    BoolSlot(f, m, s);
  } else if constexpr (std::is_same_v<M, std::string>) {
    TextSlot(f, m, s);
  } else if constexpr (std::is_enum_v<M>) {
    EnumSlot(f, m, s);
  } else {
    static_assert(kAlwaysFalse<M>, "a member type the protocol does not carry");
  }
  return s;
}

}  // namespace hpa::flight::wire::detail
