#pragma once
// A scenario's YAML tree changed at a dotted key path before it is validated: the `--set
// PATH=VALUE` of the CLI and a sweep run's drawn values (docs/design.md section 5).

#include <yaml-cpp/yaml.h>

#include <string>

namespace hpa {

/// Sets `path` (dotted; list indices written 0, 1, 2, ...) in `root` to `value`'s YAML text, or,
/// for a path written PATH+ (`--set 'events+={...}'`), appends the value to the list at PATH (a
/// missing key becomes a list of one); throws InputError naming `file` (where the set came from)
/// and the path when the path does not exist (a map may gain a missing last key; a list index
/// must name an entry) or PATH+ names something other than a list. Returns the path it set: the
/// appended entry's (`events.2`), else `path`.
std::string SetDottedPath(YAML::Node root, const std::string& path, const std::string& value,
                   const std::string& file);

}  // namespace hpa
