#pragma once
// Bad input anywhere in hpa-sim (file, key, value): the CLI maps it to exit code 2.

#include <stdexcept>
#include <string>

namespace hpa {

/// Thrown for a missing or malformed file, an unknown key, a wrong type or an out-of-range
/// value. The message names the file, the key path and what was expected.
class InputError : public std::runtime_error {
 public:
  /// Builds "FILE: KEY: WHAT" (empty parts are left out).
  InputError(const std::string& file, const std::string& key, const std::string& what);
  const std::string& file() const { return file_; }
  const std::string& key() const { return key_; }
  /// What was wrong, without the file and key.
  const std::string& detail() const { return detail_; }

 private:
  std::string file_;
  std::string key_;
  std::string detail_;
};

/// Thrown when an output (metrics.json, log.csv, a PNG, runs.jsonl) cannot be written: disk
/// full, no permission, a folder in the way. The CLI maps it to exit code 4.
class OutputError : public std::runtime_error {
 public:
  /// "cannot write PATH: WHY".
  OutputError(const std::string& path, const std::string& why)
      : std::runtime_error("cannot write " + path + (why.empty() ? "" : ": " + why)) {}
};

}  // namespace hpa
