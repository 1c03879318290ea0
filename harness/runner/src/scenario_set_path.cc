// A scenario's YAML tree changed at a dotted key path (scenario_set_path.h).

#include "harness/runner/src/scenario_set_path.h"

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <vector>

#include "hpa/models/input_error.h"
#include "hpa/models/yaml_reader.h"

namespace hpa {
namespace {

bool IsNumber(const std::string& s, double* v = nullptr) {
  char* end = nullptr;
  const double d = std::strtod(s.c_str(), &end);
  if (s.empty() || *end != '\0' || !std::isfinite(d)) return false;
  if (v) *v = d;
  return true;
}

// A list index written the one way it can be: 0, 1, 2, ... (no sign, point, exponent or leading
// zero), so one list element cannot be varied under two spellings.
bool ListIndex(const std::string& s, double* v) {
  if (s.empty() || s.size() > 9 || s.find_first_not_of("0123456789") != std::string::npos ||
      (s.size() > 1 && s[0] == '0')) {
    return false;
  }
  *v = std::stod(s);
  return true;
}

// The index `part` of the list at `list_path` with `size` entries; InputError naming the whole
// path when `part` is not one (a sign, a point, a name, past the end: a set changes an entry, it
// adds none).
size_t ListEntry(const std::string& part, size_t size, const std::string& list_path,
                 const std::string& path, const std::string& file) {
  double idx = 0.0;
  if (ListIndex(part, &idx) && idx < size) return static_cast<size_t>(idx);
  const std::string entries = size == 0 ? "it is empty"
                                        : "it has " + std::to_string(size) + " entr" +
                                              (size == 1 ? "y" : "ies") + ", indices 0 to " +
                                              std::to_string(size - 1);
  throw InputError(file, path,
                   "'" + part + "' is not an index of the list " + list_path + " (" + entries +
                       "; indices are written 0, 1, 2, ...; a set changes an entry: append one "
                       "with " +
                       list_path + "+=VALUE, e.g. --set 'events+={at: 2.0, type: impulse, "
                                   "body: payload, impulse: [0, 0, 0.1]}')");
}

// The YAML text of a set value ("0.5", "[0, 0, 1]", "hpa_mpc") as a node; malformed YAML is bad
// input naming where the value came from and its key.
YAML::Node ParseValue(const std::string& value, const std::string& path, const std::string& file) {
  try {
    return LoadYamlText(value, file);
  } catch (const InputError& e) {
    throw InputError(file, path, "malformed value '" + value + "': " + e.detail());
  }
}

// Appends `entry` to the list under `last` in `parent` (at `parent_path`); a missing key of a map
// becomes a list of one entry; returns the appended entry's path. InputError naming the path
// when it names no list.
std::string AppendToList(YAML::Node parent, const std::string& last, const std::string& parent_path,
                  const YAML::Node& entry, const std::string& path, const std::string& file) {
  const std::string list_path = parent_path.empty() ? last : parent_path + "." + last;
  YAML::Node list;
  if (parent.IsSequence()) {
    list = parent[ListEntry(last, parent.size(), parent_path, path, file)];
  } else if (parent.IsMap() || parent.IsNull()) {
    if (!parent[last] || parent[last].IsNull()) parent[last] = YAML::Node(YAML::NodeType::Sequence);
    list = parent[last];
  } else {
    throw InputError(file, path, "parent of the last key is a scalar in the base scenario");
  }
  if (!list.IsSequence()) {
    throw InputError(file, path,
                     "'" + list_path + "' is not a list in the base scenario: PATH+=VALUE appends "
                     "to a list (set a value with PATH=VALUE)");
  }
  list.push_back(entry);
  return list_path + "." + std::to_string(list.size() - 1);
}

}  // namespace

// Sets a dotted path in a YAML tree to a value, or appends the value to the list at a path
// written PATH+ (returns the path set); throws InputError if the path does not exist (maps may
// gain a missing last key; list indices must exist).
std::string SetDottedPath(YAML::Node root, const std::string& path, const std::string& value,
                          const std::string& file) {
  std::vector<std::string> parts;
  std::stringstream ss(path);
  for (std::string p; std::getline(ss, p, '.');) parts.push_back(p);
  if (parts.empty()) throw InputError(file, path, "empty key path");
  // PATH+=VALUE: the value appended to the list at PATH (a '+' anywhere else is no key's)
  const bool append = parts.back().size() > 1 && parts.back().back() == '+';
  if (append) parts.back().pop_back();
  for (const std::string& part : parts) {
    if (part.empty() || part.find('+') != std::string::npos) {
      throw InputError(file, path,
                       "'" + part +
                           "' is not a key: a path is dotted keys and list indices (events.1.at), "
                           "and PATH+=VALUE appends VALUE to the list at PATH (events+={...})");
    }
  }
  // walk with node handles; yaml-cpp nodes are references into the tree
  std::vector<YAML::Node> chain{root};
  std::string walked;
  for (size_t i = 0; i + 1 < parts.size(); ++i) {
    YAML::Node cur = chain.back();
    const std::string list_path = walked;  // the path to cur, for a list's message
    walked += (walked.empty() ? "" : ".") + parts[i];
    YAML::Node next;
    if (cur.IsSequence()) {
      next = cur[ListEntry(parts[i], cur.size(), list_path, path, file)];
    } else if (cur.IsMap()) {
      if (!cur[parts[i]]) {
        if (IsNumber(parts[i + 1])) {
          throw InputError(file, path,
                           "'" + walked + "' is not in the base scenario, so '" + parts[i + 1] +
                               "' is not an index of a list");
        }
        cur[parts[i]] = YAML::Node(YAML::NodeType::Map);
      }
      next = cur[parts[i]];
    } else {
      throw InputError(file, path, "'" + walked + "' is not a map or a list in the base scenario");
    }
    chain.push_back(next);
  }
  YAML::Node parent = chain.back();
  const std::string& last = parts.back();
  if (append) return AppendToList(parent, last, walked, ParseValue(value, path, file), path, file);
  if (parent.IsSequence()) {
    parent[ListEntry(last, parent.size(), walked, path, file)] = ParseValue(value, path, file);
  } else if (parent.IsMap() || parent.IsNull()) {
    parent[last] = ParseValue(value, path, file);
  } else {
    throw InputError(file, path, "parent of the last key is a scalar in the base scenario");
  }
  return path;
}

}  // namespace hpa
