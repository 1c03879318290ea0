// DIR/inputs.json: the text of the files a sweep was run from, kept with its results so that
// sweep-diff can say what changed between two sweeps even after the files were edited.

#include <sys/stat.h>
#include <yaml-cpp/yaml.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "hpa/models/yaml_reader.h"
#include "harness/sweeps/src/sweep_internal.h"

namespace hpa::sweep {

namespace {

using Json = nlohmann::json;

const char kInputsFile[] = "/inputs.json";

// Every scalar of a YAML node by its dotted key path (list items by index), as YAML text.
void Flatten(const YAML::Node& node, const std::string& path,
             std::map<std::string, std::string>* out) {
  if (node.IsMap()) {
    for (const auto& kv : node) {
      const std::string key = kv.first.as<std::string>();
      Flatten(kv.second, path.empty() ? key : path + "." + key, out);
    }
  } else if (node.IsSequence()) {
    for (size_t i = 0; i < node.size(); ++i) {
      Flatten(node[i], path.empty() ? std::to_string(i) : path + "." + std::to_string(i), out);
    }
  } else {
    (*out)[path] = node.IsNull() ? "null" : node.Scalar();
  }
}

// Where two texts first differ, for a file that is not YAML: "line N: A (A) vs B (B)".
std::string FirstDifferingLine(const std::string& a, const std::string& b) {
  std::istringstream sa(a), sb(b);
  std::string la, lb;
  for (int line = 1;; ++line) {
    const bool more_a = static_cast<bool>(std::getline(sa, la));
    const bool more_b = static_cast<bool>(std::getline(sb, lb));
    if (!more_a && !more_b) return "the text differs";
    if (!more_a) la = "(end)";
    if (!more_b) lb = "(end)";
    if (la != lb) {
      return "line " + std::to_string(line) + ": " + la.substr(0, 80) + " (A) vs " +
             lb.substr(0, 80) + " (B)";
    }
  }
}

}  // namespace

namespace {

// The files of a sweep's inputs as inputs.json keeps them: the sweep and base files' text, the
// csv reference's, and the data files by their hash (the MJCF scene and the profiles are long),
// params.yaml's text too, so that a changed parameter is named key by key.
Json FilesJson(const SweepSpec& spec) {
  Json files = Json::array();
  files.push_back({{"role", "sweep"}, {"path", spec.file}, {"text", spec.sweep_text}});
  files.push_back({{"role", "base"}, {"path", spec.base_path}, {"text", spec.base_text}});
  if (spec.reference_csv_text) {
    files.push_back({{"role", "reference.file"},
                     {"path", spec.reference_csv_path},
                     {"text", *spec.reference_csv_text}});
  }
  for (const auto& [role, path] : DataInputFiles()) {
    const std::string text = ReadInputFile(path, "a data file of hpa");
    Json entry = {{"role", role}, {"path", path}, {"hash", HashText(text)}};
    if (role == "params") entry["text"] = text;
    files.push_back(entry);
  }
  return files;
}

// Adds what flew beside the files: the flight stack or the stacks factor's named stacks, --runs
// and --set (each only when given).
void AddCommandLine(const SweepSpec& spec, Json* part) {
  if (!spec.flight_stack.empty()) (*part)["flight_stack"] = spec.flight_stack;
  if (!spec.flight_stacks.empty()) {
    Json stacks = Json::array();
    for (const auto& [name, command] : spec.flight_stacks) stacks.push_back({name, command});
    (*part)["flight_stacks"] = stacks;
  }
  if (spec.runs_override) (*part)["runs"] = *spec.runs_override;
  if (!spec.sets.empty()) {
    Json sets = Json::array();
    for (const auto& [key, value] : spec.sets) sets.push_back({key, value});
    (*part)["sets"] = sets;
  }
}

// Reads a list of files of inputs.json (`path` names the file in messages).
std::vector<InputFile> ReadFiles(const Json& list, const std::string& path) {
  std::vector<InputFile> files;
  for (const Json& f : list) {
    // a file kept by its hash alone compares by that hash; one kept by its text (which may come
    // without a hash) by the text's
    InputFile file{f.at("role").get<std::string>(), f.at("path").get<std::string>(), std::nullopt,
                   ""};
    if (!f.contains("text") && !f.contains("hash")) {
      throw InputError(path, "", "malformed: a file with neither its text nor its hash");
    }
    if (f.contains("text")) file.text = f.at("text").get<std::string>();
    file.hash = f.contains("hash") ? f.at("hash").get<std::string>() : HashText(*file.text);
    files.push_back(file);
  }
  return files;
}

// Reads the stack, --runs and --set of one part of inputs.json.
template <typename Part>
void ReadCommandLine(const Json& j, Part* part) {
  if (j.contains("flight_stack")) part->flight_stack = j.at("flight_stack").get<std::string>();
  if (j.contains("flight_stacks")) {
    for (const Json& stack : j.at("flight_stacks")) {
      part->flight_stacks.emplace_back(stack.at(0).get<std::string>(),
                                       stack.at(1).get<std::string>());
    }
  }
  if (j.contains("runs")) part->runs = j.at("runs").get<int>();
  if (j.contains("sets")) {
    for (const Json& set : j.at("sets")) {
      part->sets.emplace_back(set.at(0).get<std::string>(), set.at(1).get<std::string>());
    }
  }
}

}  // namespace

void WriteInputsSnapshot(const SweepSpec& spec, const std::string& dir) {
  const std::string path = dir + kInputsFile;
  struct stat st;
  const bool exists = stat(path.c_str(), &st) == 0;
  if (exists && spec.inputs_id.empty()) return;  // a resume of the same inputs keeps the first
  Json snapshot;
  if (exists) {
    try {
      snapshot = Json::parse(ReadInputFile(path, "a sweep's inputs.json"));
    } catch (const Json::exception& e) {
      throw InputError(path, "", std::string("malformed: ") + e.what());
    }
  } else if (!spec.inputs_id.empty()) {
    // the folder's first runs were recorded without inputs.json: their inputs are unknown
    snapshot = {{"sweep_id", spec.sweep_id},
                {"files", Json::array()},
                {"note", "the first runs' inputs were not recorded (an older hpa)"}};
  } else {
    snapshot = {{"sweep_id", spec.sweep_id}, {"files", FilesJson(spec)}};
    AddCommandLine(spec, &snapshot);
  }
  if (!spec.inputs_id.empty()) {
    // a part resumed with changed inputs: recorded once per inputs_id, in the order flown
    if (!snapshot.contains("resumed") || !snapshot["resumed"].is_array()) {
      snapshot["resumed"] = Json::array();
    }
    for (const Json& part : snapshot["resumed"]) {
      if (part.value("inputs_id", "") == spec.inputs_id) return;
    }
    Json part = {{"inputs_id", spec.inputs_id}, {"files", FilesJson(spec)}};
    AddCommandLine(spec, &part);
    snapshot["resumed"].push_back(part);
  }
  WriteFileAtomic(path, snapshot.dump(1, ' ', false, Json::error_handler_t::replace) + "\n");
}

std::optional<InputsSnapshot> ReadInputsSnapshot(const std::string& dir) {
  const std::string path = dir + kInputsFile;
  struct stat st;
  if (stat(path.c_str(), &st) != 0) return std::nullopt;
  InputsSnapshot snapshot;
  try {
    const Json j = Json::parse(ReadInputFile(path, "a sweep's inputs.json"));
    snapshot.sweep_id = j.at("sweep_id").get<std::string>();
    snapshot.files = ReadFiles(j.at("files"), path);
    ReadCommandLine(j, &snapshot);
    for (const Json& p : j.value("resumed", Json::array())) {
      ResumedInputs part;
      part.inputs_id = p.at("inputs_id").get<std::string>();
      part.files = ReadFiles(p.at("files"), path);
      ReadCommandLine(p, &part);
      snapshot.resumed.push_back(part);
    }
  } catch (const Json::exception& e) {
    throw InputError(path, "", std::string("malformed: ") + e.what());
  }
  return snapshot;
}

void CopyInputsSnapshot(const std::vector<std::string>& from_dirs, const std::string& sweep_id,
                        const std::string& to_dir) {
  for (const std::string& dir : from_dirs) {
    if (dir == to_dir) return;
    const std::optional<InputsSnapshot> snapshot = ReadInputsSnapshot(dir);
    if (!snapshot || snapshot->sweep_id != sweep_id) continue;
    WriteFileAtomic(to_dir + kInputsFile, ReadInputFile(dir + kInputsFile, "inputs.json"));
    return;
  }
}

namespace {

// What differs between two sweeps' command lines: the flight stack, --runs and --set.
void DescribeCommandLineChanges(const InputsSnapshot& a, const InputsSnapshot& b,
                                std::vector<std::string>* out) {
  std::vector<std::string>& changes = *out;
  if (a.flight_stack != b.flight_stack) {
    const auto shown = [](const std::string& command) {
      return command.empty() ? std::string("in process") : "'" + command + "'";
    };
    changes.push_back("flight stack: " + shown(a.flight_stack) + " (A) vs " +
                      shown(b.flight_stack) + " (B)");
  }
  if (a.flight_stacks != b.flight_stacks) {
    const auto shown = [](const std::vector<std::pair<std::string, std::string>>& stacks) {
      std::string text;
      for (const auto& [name, command] : stacks) {
        text += (text.empty() ? "" : ", ") + name + "='" + command + "'";
      }
      return text.empty() ? std::string("none") : text;
    };
    changes.push_back("flight stacks factor: " + shown(a.flight_stacks) + " (A) vs " +
                      shown(b.flight_stacks) + " (B)");
  }
  // the command line's overrides of the sweep file
  if (a.runs != b.runs) {
    const auto shown = [](const std::optional<int>& runs) {
      return runs ? std::to_string(*runs) : std::string("the file's");
    };
    changes.push_back("--runs: " + shown(a.runs) + " (A) vs " + shown(b.runs) + " (B)");
  }
  std::map<std::string, std::string> sets_a(a.sets.begin(), a.sets.end()),
      sets_b(b.sets.begin(), b.sets.end());
  for (const auto& [key, value] : sets_a) {
    const auto it = sets_b.find(key);
    const std::string other = it == sets_b.end() ? "(not set)" : it->second;
    if (other != value)
      changes.push_back("--set " + key + ": " + value + " (A) vs " + other + " (B)");
  }
  for (const auto& [key, value] : sets_b) {
    if (!sets_a.count(key))
      changes.push_back("--set " + key + ": (not set) (A) vs " + value + " (B)");
  }
}

}  // namespace

std::vector<std::string> DescribeInputChanges(const InputsSnapshot& a, const InputsSnapshot& b) {
  std::vector<std::string> changes;
  DescribeCommandLineChanges(a, b, &changes);
  for (const InputFile& fa : a.files) {
    for (const InputFile& fb : b.files) {
      if (fa.role != fb.role || fa.hash == fb.hash) continue;
      const std::string what =
          fa.role + " file " +
          (fa.path == fb.path ? fa.path : fa.path + " (A) / " + fb.path + " (B)");
      std::map<std::string, std::string> ka, kb;
      if (!fa.text || !fb.text) {
        changes.push_back(what + ": its content differs");
        continue;
      }
      if (fa.role == "reference.file") {
        changes.push_back(what + ": " + FirstDifferingLine(*fa.text, *fb.text));
        continue;
      }
      try {
        Flatten(LoadYamlText(*fa.text, fa.path), "", &ka);
        Flatten(LoadYamlText(*fb.text, fb.path), "", &kb);
      } catch (const InputError&) {
        changes.push_back(what + ": the text differs");
        continue;
      }
      std::set<std::string> keys;
      for (const auto& [k, v] : ka) keys.insert(k);
      for (const auto& [k, v] : kb) keys.insert(k);
      int listed = 0;
      for (const std::string& k : keys) {
        const auto ia = ka.find(k), ib = kb.find(k);
        const std::string va = ia == ka.end() ? "(absent)" : ia->second;
        const std::string vb = ib == kb.end() ? "(absent)" : ib->second;
        if (va == vb) continue;
        if (++listed <= 20)
          changes.push_back(what + ": " + k + ": " + va + " (A) vs " + vb + " (B)");
      }
      if (listed > 20) {
        changes.push_back(what + ": and " + std::to_string(listed - 20) + " more keys differ");
      }
      if (listed == 0) changes.push_back(what + ": the text differs, its values do not");
    }
  }
  return changes;
}

}  // namespace hpa::sweep
