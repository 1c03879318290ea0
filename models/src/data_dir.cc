#include "hpa/models/data_dir.h"

#include <unistd.h>

#include <climits>
#include <cstdlib>
#include <fstream>

namespace hpa {

std::string DataDir() {
  if (const char* env = std::getenv("HPA_DATA_DIR"); env != nullptr && *env != '\0') return env;
  char buf[PATH_MAX];
  const ssize_t n = ::readlink("/proc/self/exe", buf, sizeof buf - 1);
  if (n > 0) {
    const std::string exe(buf, static_cast<size_t>(n));
    const std::string prefix = exe.substr(0, exe.rfind('/')) + "/../share/hpa";
    if (std::ifstream(prefix + "/models/params.yaml").good()) return prefix;
  }
  return HPA_SOURCE_DIR;
}

std::string DataPath(const std::string& relative) { return DataDir() + "/" + relative; }

}  // namespace hpa
