#include "hpa/scenarios/provenance.h"

#include "hpa_version.h"

namespace hpa {

namespace {

// The compiler's own name and version macros (clang's ends in a space: trimmed).
std::string CompilerName() {
#if defined(__clang__)
  std::string name = std::string("clang ") + __clang_version__;
#elif defined(__GNUC__)
  std::string name = std::string("gcc ") + __VERSION__;
#else
  std::string name = "unknown compiler";
#endif
  while (!name.empty() && name.back() == ' ') name.pop_back();
  return name;
}

}  // namespace

const BuildProvenance& ThisBuild() {
  static const BuildProvenance build{HPA_VERSION, HPA_GIT_COMMIT, HPA_BUILD_TYPE, CompilerName()};
  return build;
}

nlohmann::ordered_json BuildToJson(const BuildProvenance& build) {
  return {{"hpa_version", build.hpa_version},
          {"commit", build.commit},
          {"build_type", build.build_type},
          {"compiler", build.compiler}};
}

BuildProvenance BuildFromJson(const nlohmann::json& json) {
  const auto field = [&](const char* key) {
    return json.is_object() && json.contains(key) && json[key].is_string()
               ? json[key].get<std::string>()
               : std::string();
  };
  return {field("hpa_version"), field("commit"), field("build_type"), field("compiler")};
}

std::string DescribeBuild(const BuildProvenance& build) {
  return "hpa " + build.hpa_version + ", commit " + build.commit + ", " + build.build_type + ", " +
         build.compiler;
}

}  // namespace hpa
