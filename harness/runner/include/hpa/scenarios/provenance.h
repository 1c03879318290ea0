#pragma once
// Which build produced a result: written into metrics.json and runs.jsonl so that a comparison
// can tell whether two results came from the same code, compiler and optimisation.

#include <nlohmann/json.hpp>
#include <string>

namespace hpa {

/// The build this process was compiled as.
struct BuildProvenance {
  std::string hpa_version;  // the project's version (CMakeLists.txt)
  std::string commit;       // git commit built, "+local-changes" when the tree was edited
  std::string build_type;   // CMAKE_BUILD_TYPE: Release, Debug, RelWithDebInfo, ...
  std::string compiler;     // compiler name and version
};

/// This process's build.
const BuildProvenance& ThisBuild();

/// The build as a JSON object {hpa_version, commit, build_type, compiler}.
nlohmann::ordered_json BuildToJson(const BuildProvenance& build);

/// The build a JSON object from BuildToJson names (missing fields empty).
BuildProvenance BuildFromJson(const nlohmann::json& json);

/// One line naming a build: "hpa 0.19.0, commit abc, Release, gcc 12.2.0".
std::string DescribeBuild(const BuildProvenance& build);

}  // namespace hpa
