#include "hpa/scenarios/reference_types.h"

#include <Eigen/Core>
#include <vector>

namespace hpa {
namespace {

// `path` relative to the folder of `scenario_file`, unless it is absolute.
std::string NextToScenario(const std::string& path, const std::string& scenario_file) {
  if (!path.empty() && path[0] == '/') return path;
  const size_t slash = scenario_file.rfind('/');
  return (slash == std::string::npos ? "" : scenario_file.substr(0, slash + 1)) + path;
}

}  // namespace

ReferenceSpec ParseReferenceBlock(const YamlMap& r, const std::optional<std::string>& file_text) {
  const ReferenceType& type =
      *FindReferenceType(r.Choice("type", ReferenceTypeNames(), ReferenceSpec().type));
  // every key of the type's table, in its order, with its range and default
  ReferenceKeyValues values;
  values.file_text = file_text;
  for (const ReferenceKey& k : type.keys) {
    if (k.size == 0) {
      values.files[k.key] = NextToScenario(r.String(k.key), r.file());
    } else if (k.size == 1) {
      values.numbers[k.key] = {k.fallback ? r.Number(k.key, k.min, k.max, *k.fallback)
                                          : r.Number(k.key, k.min, k.max)};
    } else if (!r.Has(k.key) && k.fallback) {
      values.numbers[k.key] = std::vector<double>(k.size, *k.fallback);
    } else {
      const Eigen::VectorXd v = r.Vector(k.key, k.size, k.min, k.max);
      values.numbers[k.key].assign(v.data(), v.data() + v.size());
    }
  }
  ReferenceSpec spec = ReadReferenceSpec(type, values);
  r.RejectUnknownKeys();
  return spec;
}

}  // namespace hpa
