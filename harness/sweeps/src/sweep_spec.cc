// Sweep files: loading and validating `vary`, expansion into runs, shards.

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <random>
#include <sstream>

#include "hpa/controller/reference.h"
#include "hpa/controller/reference_types.h"
#include "hpa/models/data_dir.h"
#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/models/seed_streams.h"
#include "hpa/models/yaml_reader.h"
#include "hpa/scenarios/world_profile_yaml.h"
#include "harness/cli/src/cli_parse.h"
#include "harness/sweeps/src/sweep_internal.h"

namespace hpa {
namespace sweep {

bool IsNumber(const std::string& s, double* v) {
  char* end = nullptr;
  const double d = std::strtod(s.c_str(), &end);
  if (s.empty() || *end != '\0' || !std::isfinite(d)) return false;
  if (v) *v = d;
  return true;
}

std::string FormatNumber(double v) {
  std::ostringstream out;
  out << std::setprecision(17) << v;
  return out.str();
}

std::string HashText(const std::string& text) {
  uint64_t h = 1469598103934665603ULL;  // FNV-1a
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ULL;
  std::ostringstream out;
  out << std::hex << std::setw(16) << std::setfill('0') << h;
  return out.str();
}

Scenario BuildScenario(const SweepSpec& spec, const SweepRun& run) {
  // the stack that flies the run is no key of its scenario
  std::vector<std::pair<std::string, std::string>> values;
  for (const auto& value : run.values) {
    if (value.first != kStackFactor) values.push_back(value);
  }
  // the base as it was when the sweep was loaded: an edit during the sweep changes no run
  Scenario s = spec.base_text.empty() ? LoadScenario(spec.base_path, values, spec.file)
                                      : LoadScenarioText(spec.base_text, spec.base_path, values,
                                                         spec.file, spec.reference_csv_text);
  s.seed = run.seed;
  return s;
}

}  // namespace sweep

std::string FlightStackOf(const SweepSpec& spec, const SweepRun& run) {
  if (spec.flight_stacks.empty()) return spec.flight_stack;
  for (const auto& [path, name] : run.values) {
    if (path != kStackFactor) continue;
    for (const auto& [stack_name, command] : spec.flight_stacks) {
      if (stack_name == name) return command;
    }
  }
  return "";
}

namespace {

using sweep::BuildScenario;
using sweep::FormatNumber;

std::string Dirname(const std::string& path) {
  const size_t slash = path.rfind('/');
  return slash == std::string::npos ? "." : path.substr(0, slash);
}

// One entry of `vary`: its path, exactly one of uniform | normal | grid | list, and its label.
VarySpec LoadVary(const YamlMap& vary, const std::string& path) {
  VarySpec v;
  v.path = path;
  if (v.path == kStackFactor) {
    vary.Fail(v.path,
              "the flight stack is no scenario key: fly stacks as a factor with hpa sweep "
              "--flight-stack NAME=CMD, once per stack");
  }
  if (v.path == "seed") {
    vary.Fail("seed",
              "the seed cannot be varied: each run's seed is drawn from the sweep's "
              "`seed`");
  }
  const YamlMap d = vary.Map(v.path);
  const std::vector<std::string> kinds = {"uniform", "normal", "grid", "list"};
  int found = 0;
  for (const auto& k : kinds) found += d.Has(k) ? 1 : 0;
  if (found != 1) {
    d.Fail("", "expected exactly one of uniform | normal | grid | list (and optionally label)");
  }
  if (d.Has("uniform")) {
    const Eigen::VectorXd ab = d.Vector("uniform", 2, -1e9, 1e9);
    if (ab(1) < ab(0)) d.Fail("uniform", "expected [low, high] with low <= high");
    v.kind = VarySpec::Kind::kUniform, v.a = ab(0), v.b = ab(1);
  } else if (d.Has("normal")) {
    const Eigen::VectorXd ab = d.Vector("normal", 2, -1e9, 1e9);
    if (ab(1) < 0) d.Fail("normal", "expected [mean, sigma] with sigma >= 0");
    v.kind = VarySpec::Kind::kNormal, v.a = ab(0), v.b = ab(1);
  } else {
    const std::string key = d.Has("grid") ? "grid" : "list";
    v.kind = key == "grid" ? VarySpec::Kind::kGrid : VarySpec::Kind::kList;
    const YAML::Node list = d.Node(key);
    if (!list.IsSequence() || list.size() == 0) d.Fail(key, "expected a non-empty list");
    for (const auto& item : list) {
      if (!item.IsScalar()) d.Fail(key, "expected a list of scalars");
      v.values.push_back(item.as<std::string>());
    }
  }
  v.label = d.String("label", "");
  d.RejectUnknownKeys();
  return v;
}

// Checks before anything runs that the runs are valid scenarios: each draw of a distribution,
// not only its first, is checked against its key's range, for the first kValidatedRuns runs (a
// draw beyond them that is out of range is recorded as that run's error).
void ValidateRuns(const SweepSpec& s, const std::string& path) {
  constexpr long kValidatedRuns = 2000;
  SweepSpec probe = s;
  const long cells = std::max(1L, SweepRunCount(s) / std::max(1, s.runs));
  if (cells > kValidatedRuns) {
    throw InputError(path, "vary",
                     "the grid has " + std::to_string(cells) + " cells, more than " +
                         std::to_string(kValidatedRuns) + ": split the sweep");
  }
  probe.runs = static_cast<int>(std::min<long>(s.runs, std::max(1L, kValidatedRuns / cells)));
  for (const SweepRun& run : ExpandSweep(probe)) {
    try {
      BuildScenario(s, run);
    } catch (const InputError& e) {
      // no varied value: the base scenario itself is bad
      if (run.values.empty()) throw InputError(path, "base", e.what());
      std::string values;
      for (const auto& [key, value] : run.values) {
        values += (values.empty() ? "" : " ") + key + "=" + value;
      }
      throw InputError(path, "vary",
                       "run " + std::to_string(run.index) + " (" + values +
                           ") is not a valid scenario: " + e.what());
    }
  }
}

// Whether a vary entry takes more than one value: a grid or list of two distinct values, a
// uniform of some width, a normal of some spread.
bool TakesSeveralValues(const VarySpec& v) {
  switch (v.kind) {
    case VarySpec::Kind::kUniform:
      return v.b > v.a;
    case VarySpec::Kind::kNormal:
      return v.b > 0.0;
    case VarySpec::Kind::kGrid:
    case VarySpec::Kind::kList:
      for (const std::string& value : v.values) {
        double x = 0.0, y = 0.0;
        const std::string& first = v.values.front();
        const bool same =
            sweep::IsNumber(value, &x) && sweep::IsNumber(first, &y) ? x == y : value == first;
        if (!same) return true;
      }
      return false;
  }
  return false;
}

// The scenario keys only the flight code reads (the hello's `config` beside the params and the
// reference): the controller and its settings, the estimator variant and its tension cue. A
// separate stack flies its own code, so these change nothing it flies.
bool FlightCodeKey(const std::string& path) {
  return path == "controller" || path.rfind("controller.", 0) == 0 ||
         path == "estimation.estimator" || path == "estimation.slack_tension_cue";
}

// Whether the stack `command` flies the hello's setting at `path`: hpa-flight builds the
// scenario's controller and estimator from the hello, unless its --controller or --estimator
// names one of its own.
bool StackReadsFlightCode(const std::string& command, const std::string& path) {
  std::istringstream words(command);
  std::string program, word;
  words >> program;
  if (program.substr(program.rfind('/') + 1) != "hpa-flight") return false;
  const std::string own = path.rfind("estimation.", 0) == 0 ? "--estimator" : "--controller";
  while (words >> word) {
    if (word == own || word.rfind(own + "=", 0) == 0) return false;
  }
  return true;
}

// A sweep flown by a separate stack that varies a key only the in-process flight code reads
// would fly the same stack on the same seeds once per value, under as many labels (n doubled,
// intervals too narrow): refused before any run, naming the key.
void RefuseKeysTheStackIgnores(const SweepSpec& s, const std::string& path) {
  std::vector<std::string> stacks;
  if (!s.flight_stack.empty()) stacks.push_back(s.flight_stack);
  for (const auto& [name, command] : s.flight_stacks) stacks.push_back(command);
  for (const std::string& stack : stacks) {
    for (const VarySpec& v : s.vary) {
      if (!FlightCodeKey(v.path) || !TakesSeveralValues(v) || StackReadsFlightCode(stack, v.path)) {
        continue;
      }
      throw InputError(path, "vary." + v.path,
                       "takes several values, but the flight stack '" + stack +
                           "' flies its own flight code and ignores " + v.path +
                           ": each value would fly the same stack on the same seeds under another "
                           "label. Leave " +
                           v.path +
                           " out of vary (sweep it in process), or fly the stacks as the "
                           "factor: --flight-stack NAME=CMD, once per stack");
    }
  }
}

// The named stacks of --flight-stack NAME=CMD (twice or more) as the sweep's last grid factor:
// each NAME a safe name used once, each CMD a command FlightStackCommandError accepts.
void AddStackFactor(const std::vector<std::pair<std::string, std::string>>& stacks, SweepSpec* s) {
  VarySpec factor;
  factor.path = kStackFactor;
  factor.kind = VarySpec::Kind::kGrid;
  factor.label = "flight stack";
  for (const auto& [name, command] : stacks) {
    const auto fail = [&, name = name](const std::string& why) {
      throw InputError("", "--flight-stack", "'" + name + "=...': " + why);
    };
    if (!IsSafeName(name)) {
      fail("NAME '" + name +
           "' is not a safe name: 1 to 64 of A-Z a-z 0-9 _ - ., not starting "
           "with '.'");
    }
    if (std::find(factor.values.begin(), factor.values.end(), name) != factor.values.end()) {
      fail("NAME '" + name + "' is given twice");
    }
    if (const std::string why = FlightStackCommandError(command); !why.empty()) fail(why);
    factor.values.push_back(name);
  }
  s->flight_stacks = stacks;
  s->flight_stack.clear();
  s->vary.push_back(factor);
}

// The command line's --set PATH=VALUE: each must leave the vary keys to `vary` (a set on a
// varied key, inside one or holding one would overwrite draws or be overwritten by them), and
// the base with the sets alone must be a valid scenario (the message names --set).
void CheckSets(const SweepSpec& s) {
  for (const auto& [set_key, value] : s.sets) {
    // `PATH+=VALUE` appends to the list at PATH: the same key for this check
    const std::string key =
        !set_key.empty() && set_key.back() == '+' ? set_key.substr(0, set_key.size() - 1) : set_key;
    for (const VarySpec& v : s.vary) {
      const auto inside = [](const std::string& a, const std::string& b) {
        return a == b || (a.size() > b.size() && a.rfind(b + ".", 0) == 0);
      };
      if (inside(key, v.path) || inside(v.path, key)) {
        throw InputError("", "--set " + key,
                         "the sweep varies " + v.path + ": --set cannot change a varied key " +
                             "(change its `vary:` entry instead)");
      }
    }
  }
  if (s.sets.empty()) return;
  try {
    LoadScenarioText(s.base_text, s.base_path, s.sets, "--set", s.reference_csv_text);
  } catch (const InputError& e) {
    throw InputError("", "--set", std::string("the base scenario with the sets: ") + e.what());
  }
}

}  // namespace

// The base's reference CSV, read once when the sweep is loaded: every run flies this text, so
// an edit during the sweep or before a resume changes no run (a resume with an edited CSV is
// refused by the sweep_id). A sweep that varies reference.file reads each run's own file.
void SnapshotReferencedFiles(SweepSpec* s) {
  for (const VarySpec& v : s->vary) {
    if (v.path.rfind("reference", 0) == 0) return;
  }
  // only the reference block is read here: the runs are validated, with their values, later
  const YAML::Node reference = LoadYamlText(s->base_text, s->base_path)["reference"];
  if (!reference.IsMap() || !reference["type"] || !reference["type"].IsScalar()) return;
  // a type that reads a file names it by its file key (the registry's, whatever the type)
  const ReferenceType* type = FindReferenceType(reference["type"].Scalar());
  const ReferenceKey* file_key = type == nullptr ? nullptr : FileKeyOf(*type);
  if (file_key == nullptr) return;
  const YAML::Node file_node = reference[file_key->key];
  if (!file_node || !file_node.IsScalar()) return;
  std::string file = file_node.Scalar();
  if (file.empty() || file[0] != '/') file = Dirname(s->base_path) + "/" + file;
  s->reference_csv_path = file;
  s->reference_csv_text = ReadInputFile(file, "a reference CSV", kMaxReferenceCsvBytes);
}

SweepSpec LoadSweep(const std::string& path, const std::string& flight_stack) {
  SweepOverrides overrides;
  overrides.flight_stack = flight_stack;
  return LoadSweep(path, overrides);
}

SweepSpec LoadSweep(const std::string& path, const SweepOverrides& overrides) {
  const std::string& flight_stack = overrides.flight_stack;
  SweepSpec s;
  s.file = path;
  s.sweep_text = ReadYamlFile(path);
  const YAML::Node root_node = LoadYamlText(s.sweep_text, path);
  if (!root_node.IsMap()) throw InputError(path, "", "expected a YAML map at the top level");
  const YamlMap root(root_node, path, "");
  const std::string base = root.String("base");
  s.base_path = (!base.empty() && base[0] == '/') ? base : Dirname(path) + "/" + base;
  try {
    s.base_text = ReadYamlFile(s.base_path);
  } catch (const InputError& e) {
    throw InputError(path, "base", e.what());
  }
  s.runs = static_cast<int>(root.Integer("runs", 1, 1000000));
  if (overrides.runs) {
    if (*overrides.runs < 1 || *overrides.runs > 1000000) {
      throw InputError("", "--runs",
                       "expected 1 .. 1000000 draws, got " + std::to_string(*overrides.runs));
    }
    s.runs = *overrides.runs;
    s.runs_override = overrides.runs;
  }
  s.sets = overrides.sets;
  s.seed = static_cast<unsigned long>(root.Integer("seed", 0, 4294967295L, 1));
  s.time_limit_s = root.Number("time_limit", 1.0, 1e6, 600.0);
  s.flight_stack = root.String("flight_stack", "");
  if (root.Has("flight_stack")) {
    const std::string why = FlightStackCommandError(s.flight_stack);
    if (!why.empty()) root.Fail("flight_stack", why);
  }
  if (!flight_stack.empty()) {
    const std::string why = FlightStackCommandError(flight_stack);
    if (!why.empty()) throw InputError("", "--flight-stack", why);
    s.flight_stack = flight_stack;
  }
  if (root.Has("vary")) {
    const YamlMap vary = root.Map("vary");
    const YAML::Node node = root.Node("vary");
    for (const auto& kv : node) s.vary.push_back(LoadVary(vary, kv.first.as<std::string>()));
  }
  root.RejectUnknownKeys();
  if (!overrides.flight_stacks.empty()) AddStackFactor(overrides.flight_stacks, &s);

  if (SweepRunCount(s) > kMaxSweepRuns) {
    throw InputError(path, "runs",
                     "runs times the grid's cells is over " + std::to_string(kMaxSweepRuns) +
                         " runs: split the sweep");
  }
  RefuseKeysTheStackIgnores(s, path);
  SnapshotReferencedFiles(&s);
  CheckSets(s);
  ValidateRuns(s, path);
  // the id hashes every input: the sweep and base files, the reference CSV, the data files
  // every run reads (params, the MJCF scene, the world profiles) and the flight stack that flies
  // (absent in process, so a sweep without one keeps its id)
  std::string inputs = s.sweep_text + "\n--base--\n" + s.base_text;
  if (s.reference_csv_text) inputs += "\n--reference.file--\n" + *s.reference_csv_text;
  if (!s.flight_stack.empty()) inputs += "\n--flight_stack--\n" + s.flight_stack;
  for (const auto& [name, command] : s.flight_stacks) {
    inputs += "\n--flight_stacks--\n" + name + "=" + command;
  }
  // the command line's overrides, absent when none (a sweep without them keeps its id)
  if (s.runs_override) inputs += "\n--runs--\n" + std::to_string(*s.runs_override);
  for (const auto& [key, value] : s.sets) inputs += "\n--set--\n" + key + "=" + value;
  for (const auto& [role, file] : DataInputFiles()) {
    inputs += "\n--" + role + "--\n" + ReadInputFile(file, "a data file of hpa");
  }
  s.sweep_id = sweep::HashText(inputs);
  return s;
}

std::vector<std::pair<std::string, std::string>> DataInputFiles() {
  std::vector<std::pair<std::string, std::string>> files = {
      {"params", DefaultParamsPath()}, {"scene", DataPath("models/scene.xml")}};
  for (const std::string& name : WorldProfileNames()) {
    files.emplace_back("profile " + name, DataPath("models/profiles/" + name + ".yaml"));
  }
  return files;
}

long SweepRunCount(const SweepSpec& spec) {
  long cells = 1;
  for (const VarySpec& v : spec.vary) {
    if (v.kind != VarySpec::Kind::kGrid) continue;
    cells *= std::max<long>(1, static_cast<long>(v.values.size()));
    if (cells > kMaxSweepRuns) return kMaxSweepRuns + 1;  // no overflow past the limit
  }
  return std::min(cells * spec.runs, kMaxSweepRuns + 1);
}

std::vector<SweepRun> ExpandSweep(const SweepSpec& spec) {
  // grid cells: the cartesian product of every grid entry, in file order
  std::vector<std::vector<std::pair<std::string, std::string>>> cells{{}};
  for (const VarySpec& v : spec.vary) {
    if (v.kind != VarySpec::Kind::kGrid) continue;
    std::vector<std::vector<std::pair<std::string, std::string>>> next;
    for (const auto& cell : cells) {
      for (const auto& value : v.values) {
        auto c = cell;
        c.emplace_back(v.path, value);
        next.push_back(c);
      }
    }
    cells = next;
  }
  std::vector<SweepRun> runs;
  for (int d = 0; d < spec.runs; ++d) {
    // each draw has its own generator: its values do not depend on the other draws
    const uint64_t draw_seed = SplitMix64(spec.seed * 1000003ULL + static_cast<uint64_t>(d));
    std::mt19937_64 rng(draw_seed);
    std::vector<std::pair<std::string, std::string>> drawn;
    for (const VarySpec& v : spec.vary) {
      switch (v.kind) {
        case VarySpec::Kind::kUniform:
          drawn.emplace_back(v.path,
                             FormatNumber(std::uniform_real_distribution<double>(v.a, v.b)(rng)));
          break;
        case VarySpec::Kind::kNormal:
          drawn.emplace_back(
              v.path,
              FormatNumber(v.b > 0 ? std::normal_distribution<double>(v.a, v.b)(rng) : v.a));
          break;
        case VarySpec::Kind::kList:
          drawn.emplace_back(v.path, v.values[d % v.values.size()]);
          break;
        case VarySpec::Kind::kGrid:
          break;
      }
    }
    for (size_t g = 0; g < cells.size(); ++g) {
      SweepRun r;
      r.index = static_cast<int>(d * cells.size() + g);
      r.draw = d;
      r.seed = static_cast<unsigned long>(SplitMix64(draw_seed) & 0xFFFFFFFFULL);
      r.values = drawn;
      r.values.insert(r.values.end(), cells[g].begin(), cells[g].end());
      r.values.insert(r.values.end(), spec.sets.begin(), spec.sets.end());
      runs.push_back(r);
    }
  }
  return runs;
}

std::vector<SweepRun> SelectShard(const std::vector<SweepRun>& runs, int shard_k, int shard_n) {
  std::vector<SweepRun> out;
  for (const SweepRun& r : runs) {
    if (r.index % shard_n == shard_k - 1) out.push_back(r);
  }
  return out;
}

}  // namespace hpa
