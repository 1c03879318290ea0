#include "hpa/models/data_dir.h"

#include <unistd.h>

#include <climits>
#include <cstdlib>
#include <fstream>

#include "hpa/models/input_error.h"

namespace hpa {
namespace {

bool HoldsData(const std::string& dir) { return std::ifstream(dir + "/models/params.yaml").good(); }

}  // namespace

std::string DataDir() {
  if (const char* env = std::getenv("HPA_DATA_DIR"); env != nullptr && *env != '\0') {
    if (!HoldsData(env)) {
      throw InputError(env, "HPA_DATA_DIR",
                       "holds no models/params.yaml: expected hpa's data folder (an installed "
                       "prefix's share/hpa, or the source tree)");
    }
    return env;
  }
  std::string exe;
  char buf[PATH_MAX];
  const ssize_t n = ::readlink("/proc/self/exe", buf, sizeof buf - 1);
  if (n > 0) exe.assign(buf, static_cast<size_t>(n));
  const std::string prefix = exe.substr(0, exe.rfind('/')) + "/../share/hpa";
  if (!exe.empty() && HoldsData(prefix)) return prefix;
  // the source tree only for programs of the build tree it was built into: an installed program
  // never reads a source tree that happens to be on the machine
  const std::string build_dir = HPA_BINARY_DIR;
  if (exe.rfind(build_dir + "/", 0) == 0) return HPA_SOURCE_DIR;
  throw InputError("", "data folder",
                   "not found: $HPA_DATA_DIR is unset, " + prefix +
                       " holds no models/params.yaml, and " + exe +
                       " is not a program of the build tree " + build_dir +
                       " (set HPA_DATA_DIR to an installed prefix's share/hpa)");
}

std::string DataPath(const std::string& relative) { return DataDir() + "/" + relative; }

}  // namespace hpa
