#pragma once
// Params as YAML: parsing a params.yaml document and changing some of its values (a scenario's
// `params:` block), validated by the same loader, so a changed value has params.yaml's ranges.

#include <yaml-cpp/yaml.h>

#include <string>

#include "hpa/models/params.h"
#include "hpa/models/yaml_reader.h"

namespace hpa {

/// Params from a parsed params.yaml document; InputError names the file and key.
Params ParseParams(const YamlMap& root);

/// `params` as a params.yaml document (every key; doubles with all their digits).
YAML::Node ParamsToYaml(const Params& params);

/// `base` with the values of `overrides` (a map shaped like params.yaml, e.g.
/// {cable: {length_m: 0.8}}) in place of its own, checked as params.yaml is; an InputError
/// names `file` and the key as `params.SECTION.KEY`.
Params ParamsWithOverrides(const Params& base, const YAML::Node& overrides,
                           const std::string& file);

}  // namespace hpa
