#pragma once
// Strict YAML access: every read names the file and key path on failure, and unknown keys are
// errors. Shared by params.yaml, scenario and sweep loading.

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace hpa {

/// Parses a YAML file; throws InputError naming the file if it is missing, not a regular file
/// (a directory) or malformed.
YAML::Node LoadYamlFile(const std::string& file);

/// The text of a YAML file (checked as LoadYamlFile checks it).
std::string ReadYamlFile(const std::string& file);

/// Parses YAML text of one document; `file` names it in messages (InputError if malformed or
/// holding more than one document).
YAML::Node LoadYamlText(const std::string& text, const std::string& file);

/// A view of one YAML map in one file, at a dotted key path; throws InputError on bad input.
class YamlMap {
 public:
  /// Wraps `node` (must be a map) found at `path` (dotted, "" for the root) of `file`.
  YamlMap(YAML::Node node, std::string file, std::string path);

  /// Loads a file whose root is a map; throws InputError if missing or malformed.
  static YamlMap LoadFile(const std::string& file);

  bool Has(const std::string& key) const;
  /// Required number in [min, max].
  double Number(const std::string& key, double min, double max) const;
  /// Optional number in [min, max] with a default.
  double Number(const std::string& key, double min, double max, double fallback) const;
  /// Required integer in [min, max].
  long Integer(const std::string& key, long min, long max) const;
  long Integer(const std::string& key, long min, long max, long fallback) const;
  bool Bool(const std::string& key, bool fallback) const;
  std::string String(const std::string& key) const;
  std::string String(const std::string& key, const std::string& fallback) const;
  /// String that must be one of `allowed`.
  std::string Choice(const std::string& key, const std::vector<std::string>& allowed,
                     const std::string& fallback) const;
  /// Fixed-size list of numbers, each in [min, max].
  Eigen::VectorXd Vector(const std::string& key, int size, double min, double max) const;
  /// Sub-map; required.
  YamlMap Map(const std::string& key) const;
  /// Raw node (for lists); marks the key as read.
  YAML::Node Node(const std::string& key) const;

  /// Throws InputError naming the first key that was never read (an unknown key).
  void RejectUnknownKeys() const;

  /// Throws InputError for this map's `key` with the message `what`.
  [[noreturn]] void Fail(const std::string& key, const std::string& what) const;

  const std::string& file() const { return file_; }
  const std::string& path() const { return path_; }
  /// Dotted path of a key in this map.
  std::string KeyPath(const std::string& key) const;

 private:
  YAML::Node Get(const std::string& key) const;

  YAML::Node node_;
  std::string file_;
  std::string path_;
  mutable std::set<std::string> read_;
  mutable std::set<std::string> asked_;  // every key looked up (Has or Get): the valid ones
};

}  // namespace hpa
