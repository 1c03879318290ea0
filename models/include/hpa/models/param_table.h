#pragma once
// Parameters declared once: one table per config struct (key, unit, range, description, the
// member it sets), beside the struct. The YAML loaders read a section through it
// (ReadParamTable, models/yaml), `--set` goes through the same loaders, and `hpa schema` and
// the docs print it (ParamTableMarkdown) with each default taken from the struct itself.

#include <Eigen/Core>
#include <array>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace hpa {

/// A 4-vector stored unaligned (a 16-byte-aligned member would change the alignment of every
/// struct that embeds its owner).
using Vector4dUnaligned = Eigen::Matrix<double, 4, 1, Eigen::DontAlign>;

/// One parameter of a config struct C.
template <class C>
struct ParamDecl {
  std::string key;   // as written in YAML
  std::string unit;  // "s", "m", "N s/m", "-" for a pure number, "" for a switch
  double min = 0.0;  // allowed range (each element of a vector or matrix; unused for a switch)
  double max = 0.0;
  std::string description;  // one line: what it is and, where it has one, its source
  std::variant<double C::*, bool C::*, int C::*, Eigen::Vector3d C::*, Vector4dUnaligned C::*,
               Eigen::Matrix3d C::*>
      member;
  std::string wire_key = "";  // its name in the lockstep protocol's JSON ("": the YAML key)
  // a vector whose elements have ranges of their own (PX4's per-axis limits): one [min, max]
  // per element, the first element_range_count of them; 0: every element in [min, max]
  int element_range_count = 0;
  std::array<std::pair<double, double>, 4> element_ranges{};
};

/// The allowed range of element `i` of the parameter `d` (its own, or the declaration's).
template <class C>
std::pair<double, double> ElementRange(const ParamDecl<C>& d, size_t i) {
  return static_cast<int>(i) < d.element_range_count ? d.element_ranges[i]
                                                      : std::make_pair(d.min, d.max);
}

/// The parameters of one config struct, in the order they are documented.
template <class C>
struct ParamTable {
  std::string section;      // its YAML section ("latency", "rate_loop")
  std::string description;  // one line
  std::vector<ParamDecl<C>> params;
};

/// The declaration of `member` in `tables` (std::out_of_range when none declares it): code that
/// checks or clamps one field elsewhere takes its range from here rather than spelling it again.
template <class C, class M>
const ParamDecl<C>& FindParamDecl(const std::vector<ParamTable<C>>& tables, M C::*member) {
  for (const ParamTable<C>& table : tables) {
    for (const ParamDecl<C>& d : table.params) {
      const auto* held = std::get_if<M C::*>(&d.member);
      if (held != nullptr && *held == member) return d;
    }
  }
  throw std::out_of_range("no parameter declares this member");
}

/// `value` brought into the declared range of `d` (a drawn value that left it).
template <class C>
double ClampToDecl(const ParamDecl<C>& d, double value) {
  return value < d.min ? d.min : (value > d.max ? d.max : value);
}

/// Whether `value` lies in the declared range of `d` (false for NaN).
template <class C>
bool InDeclRange(const ParamDecl<C>& d, double value) {
  return value >= d.min && value <= d.max;
}

/// Checks `value` of the parameter `key` of `table` against its declared range; throws
/// std::invalid_argument "PREFIXkey: expected MIN to MAX, got VALUE" (code that builds a config
/// without the YAML loader gets the loader's range).
template <class C>
void CheckParamValue(const ParamTable<C>& table, const std::string& prefix, const std::string& key,
                     double value, size_t element = 0) {
  for (const ParamDecl<C>& d : table.params) {
    if (d.key != key) continue;
    const auto [min, max] = ElementRange(d, element);
    if (!(value >= min && value <= max)) {
      std::ostringstream what;
      what << prefix << key;
      if (d.element_range_count > 0) what << "." << element;
      what << ": expected " << min << " to " << max << ", got " << value;
      throw std::invalid_argument(what.str());
    }
    return;
  }
  throw std::invalid_argument(prefix + key + ": not a declared parameter");
}

/// Checks every numeric field of `config` against its declaration in `table` (each element of a
/// vector or matrix too); throws std::invalid_argument "PREFIXkey: expected MIN to MAX, got V".
template <class C>
void CheckParamTable(const ParamTable<C>& table, const std::string& prefix, const C& config) {
  for (const ParamDecl<C>& d : table.params) {
    std::visit(
        [&](auto member) {
          using T = std::decay_t<decltype(config.*member)>;
          if constexpr (std::is_same_v<T, double> || std::is_same_v<T, int>) {
            CheckParamValue(table, prefix, d.key, static_cast<double>(config.*member));
          } else if constexpr (!std::is_same_v<T, bool>) {
            const auto& m = config.*member;
            for (Eigen::Index i = 0; i < m.size(); ++i) {
              CheckParamValue(table, prefix, d.key, m.data()[i], static_cast<size_t>(i));
            }
          }
        },
        d.member);
  }
}

/// Text of one value as the tables print it.
inline std::string ParamValueText(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}
inline std::string ParamValueText(bool v) { return v ? "true" : "false"; }
inline std::string ParamValueText(int v) { return std::to_string(v); }
/// A vector or matrix as a YAML flow list ([1, 2, 3]; a matrix as its list of rows).
template <typename Derived>
std::string ParamValueText(const Eigen::MatrixBase<Derived>& m) {
  std::string text = "[";
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    if (m.cols() == 1) {
      text += (i ? ", " : "") + ParamValueText(static_cast<double>(m(i, 0)));
      continue;
    }
    text += std::string(i ? ", " : "") + "[";
    for (Eigen::Index j = 0; j < m.cols(); ++j) {
      text += (j ? ", " : "") + ParamValueText(static_cast<double>(m(i, j)));
    }
    text += "]";
  }
  return text + "]";
}

/// A Markdown table of `table`: key, unit, range, the value in `values` (a struct read from a
/// profile, or the defaults: C{}) and the description. `prefix` goes before each key
/// ("world.latency.").
template <class C>
std::string ParamTableMarkdown(const ParamTable<C>& table, const C& values,
                               const std::string& prefix, const std::string& value_header) {
  std::string md =
      "| key | unit | range | " + value_header + " | meaning |\n|---|---|---|---|---|\n";
  for (const ParamDecl<C>& d : table.params) {
    std::string value, range;
    std::visit(
        [&](auto member) {
          using T = std::decay_t<decltype(values.*member)>;
          value = ParamValueText(values.*member);
          if constexpr (std::is_same_v<T, bool>) {
            range = "true / false";
          } else if (d.element_range_count == 0) {
            range = ParamValueText(d.min) + " to " + ParamValueText(d.max);
          } else {
            for (size_t i = 0; static_cast<int>(i) < d.element_range_count; ++i) {
              range += (i ? " / " : "") + ParamValueText(d.element_ranges[i].first) + " to " +
                       ParamValueText(d.element_ranges[i].second);
            }
          }
        },
        d.member);
    md += "| `" + prefix + d.key + "` | " + d.unit + " | " + range + " | " + value + " | " +
          d.description + " |\n";
  }
  return md;
}

}  // namespace hpa
