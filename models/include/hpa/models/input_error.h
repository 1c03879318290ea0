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

 private:
  std::string file_;
  std::string key_;
};

}  // namespace hpa
