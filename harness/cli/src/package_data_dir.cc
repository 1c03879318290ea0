// UsePackageDataDir (hpa/scenarios/cli.h): the data folder of a program built against an
// installed hpa and run from outside hpa's prefix.

#include <cstdlib>
#include <fstream>
#include <string>

#include "hpa/models/data_dir.h"
#include "hpa/models/input_error.h"
#include "hpa/scenarios/cli.h"

namespace hpa {

void UsePackageDataDir(const std::string& package_data_dir) {
  if (const char* env = std::getenv("HPA_DATA_DIR"); env != nullptr && *env != '\0') return;
  try {
    DataDir();  // the program's own: its ../share/hpa, or a build tree's sources
    return;
  } catch (const InputError&) {
    // none of its own: the package's, if it is still there
  }
  if (package_data_dir.empty() || !std::ifstream(package_data_dir + "/models/params.yaml").good()) {
    return;
  }
  ::setenv("HPA_DATA_DIR", package_data_dir.c_str(), /*overwrite=*/1);
}

}  // namespace hpa
