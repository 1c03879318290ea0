#pragma once
// Reads a config struct's section of a YAML file through its ParamTable: every key of the table
// that is present is read and range-checked into its member (absent keys keep the struct's
// value), and a key the table does not declare is an InputError listing the valid keys.

#include <type_traits>
#include <variant>

#include "hpa/models/param_table.h"
#include "hpa/models/yaml_reader.h"

namespace hpa {

/// Reads a matrix given as a list of rows, each element in [min, max].
Eigen::Matrix3d ReadMatrix3(const YamlMap& map, const std::string& key, double min, double max);

/// Reads the keys of `table` from `map` into `*config` (each element of a vector within its own
/// range where the declaration gives one per element); rejects unknown keys of `map`. With
/// `required`, every declared key must be present (a file that is the one source of its
/// numbers); otherwise an absent key keeps the struct's value.
template <class C>
void ReadParamTable(const YamlMap& map, const ParamTable<C>& table, C* config,
                    bool required = false) {
  for (const ParamDecl<C>& d : table.params) {
    if (required && !map.Has(d.key)) map.Fail(d.key, "missing required key");
    std::visit(
        [&](auto member) {
          using T = std::decay_t<decltype(config->*member)>;
          if constexpr (std::is_same_v<T, bool>) {
            config->*member = map.Bool(d.key, config->*member);
          } else if constexpr (std::is_same_v<T, int>) {
            config->*member = static_cast<int>(map.Integer(
                d.key, static_cast<long>(d.min), static_cast<long>(d.max), config->*member));
          } else if constexpr (std::is_same_v<T, double>) {
            config->*member = map.Number(d.key, d.min, d.max, config->*member);
          } else if constexpr (std::is_same_v<T, Eigen::Matrix3d>) {
            if (map.Has(d.key)) config->*member = ReadMatrix3(map, d.key, d.min, d.max);
          } else {
            if (map.Has(d.key)) {
              const T value =
                  map.Vector(d.key, static_cast<int>(T::RowsAtCompileTime), d.min, d.max);
              for (size_t i = 0; static_cast<int>(i) < d.element_range_count; ++i) {
                const auto [min, max] = ElementRange(d, i);
                const double v = value(static_cast<Eigen::Index>(i));
                if (!(v >= min && v <= max)) {
                  map.Fail(d.key, "element " + std::to_string(i) + ": expected " +
                                      ParamValueText(min) + " to " + ParamValueText(max) +
                                      ", got " + ParamValueText(v));
                }
              }
              config->*member = value;
            }
          }
        },
        d.member);
  }
  map.RejectUnknownKeys();
}

}  // namespace hpa
