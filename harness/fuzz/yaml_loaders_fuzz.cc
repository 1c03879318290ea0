// libFuzzer target for the scenario and sweep YAML loaders: any input must either load into
// finite values or be refused with an InputError; anything else (another exception, an abort, a
// sanitizer report, a hang) is a failure. Built with -DHPA_FUZZ=ON (clang only).

#include <unistd.h>

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "hpa/models/input_error.h"
#include "hpa/scenarios/scenario.h"
#include "hpa/scenarios/sweep.h"

namespace {

// A private folder with a valid base scenario, so fuzzed sweeps can name `base: base.yaml`.
const std::string& WorkDir() {
  static const std::string dir = [] {
    char tmpl[] = "/tmp/hpa-fuzz.XXXXXX";
    const char* made = mkdtemp(tmpl);
    if (made == nullptr) std::abort();
    std::ofstream(std::string(made) + "/base.yaml")
        << "name: fuzz_base\nduration: 2.0\ncontroller: {type: geometric}\n"
           "estimation: {ground_truth: true, camera: analytic}\n"
           "reference: {type: hover, payload_position: [0, 0, 0.7]}\n"
           "events:\n  - {at: 0.5, type: impulse, body: payload, impulse: [0, 0, 0.1]}\n";
    return std::string(made);
  }();
  return dir;
}

void Write(const std::string& path, const uint8_t* data, size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
}

void Check(bool finite, const char* what) {
  if (!finite) {
    std::fprintf(stderr, "accepted a non-finite %s\n", what);
    std::abort();
  }
}

// True for a scalar that reads as a NaN or an infinity (C or YAML spelling).
bool IsNonFiniteNumber(const std::string& text) {
  std::string lower;
  for (char c : text) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (const char* yaml : {".nan", ".inf", "+.inf", "-.inf"}) {
    if (lower == yaml) return true;
  }
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  return end != text.c_str() && *end == '\0' && !std::isfinite(v);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string scenario_path = WorkDir() + "/scenario.yaml";
  const std::string sweep_path = WorkDir() + "/sweep.yaml";
  Write(scenario_path, data, size);
  Write(sweep_path, data, size);
  try {
    const hpa::Scenario s = hpa::LoadScenario(scenario_path);
    Check(std::isfinite(s.duration_s) && s.duration_s > 0, "duration");
    Check(s.reference.payload_position_W_m.allFinite(), "reference position");
  } catch (const hpa::InputError&) {
  }
  try {
    const hpa::SweepSpec spec = hpa::LoadSweep(sweep_path);
    if (hpa::SweepRunCount(spec) <= 100) {
      for (const auto& run : hpa::ExpandSweep(spec)) {
        for (const auto& [path, value] : run.values) {
          (void)path;
          Check(!IsNonFiniteNumber(value), "drawn value");
        }
      }
    }
  } catch (const hpa::InputError&) {
  }
  return 0;
}
