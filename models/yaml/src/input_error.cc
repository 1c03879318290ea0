#include "hpa/models/input_error.h"

namespace hpa {
namespace {

std::string Compose(const std::string& file, const std::string& key, const std::string& what) {
  std::string out;
  if (!file.empty()) out += file + ": ";
  if (!key.empty()) out += "key '" + key + "': ";
  return out + what;
}

}  // namespace

InputError::InputError(const std::string& file, const std::string& key, const std::string& what)
    : std::runtime_error(Compose(file, key, what)), file_(file), key_(key), detail_(what) {}

}  // namespace hpa
