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
#include "scenarios/src/tools/sweep/sweep_internal.h"

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

void WriteInputsSnapshot(const SweepSpec& spec, const std::string& dir) {
  struct stat st;
  if (stat((dir + kInputsFile).c_str(), &st) == 0) return;  // a resume keeps the first
  Json files = Json::array();
  files.push_back({{"role", "sweep"}, {"path", spec.file}, {"text", spec.sweep_text}});
  files.push_back({{"role", "base"}, {"path", spec.base_path}, {"text", spec.base_text}});
  if (spec.reference_csv_text) {
    files.push_back({{"role", "reference.file"},
                     {"path", spec.reference_csv_path},
                     {"text", *spec.reference_csv_text}});
  }
  // the data files by their hash (the MJCF scene and the profiles are long): params.yaml's text
  // too, so that a changed parameter is named key by key
  for (const auto& [role, path] : DataInputFiles()) {
    const std::string text = ReadInputFile(path, "a data file of hpa");
    Json entry = {{"role", role}, {"path", path}, {"hash", HashText(text)}};
    if (role == "params") entry["text"] = text;
    files.push_back(entry);
  }
  Json snapshot = {{"sweep_id", spec.sweep_id}, {"files", files}};
  if (!spec.flight_stack.empty()) snapshot["flight_stack"] = spec.flight_stack;
  WriteFileAtomic(dir + kInputsFile,
                  snapshot.dump(1, ' ', false, Json::error_handler_t::replace) + "\n");
}

std::optional<InputsSnapshot> ReadInputsSnapshot(const std::string& dir) {
  const std::string path = dir + kInputsFile;
  struct stat st;
  if (stat(path.c_str(), &st) != 0) return std::nullopt;
  InputsSnapshot snapshot;
  try {
    const Json j = Json::parse(ReadInputFile(path, "a sweep's inputs.json"));
    snapshot.sweep_id = j.at("sweep_id").get<std::string>();
    if (j.contains("flight_stack")) snapshot.flight_stack = j.at("flight_stack").get<std::string>();
    for (const Json& f : j.at("files")) {
      // a file kept by its hash alone compares by that hash; one kept by its text (which
      // may come without a hash) by the text's
      InputFile file{f.at("role").get<std::string>(), f.at("path").get<std::string>(),
                     std::nullopt, ""};
      if (!f.contains("text") && !f.contains("hash")) {
        throw InputError(path, "", "malformed: a file with neither its text nor its hash");
      }
      if (f.contains("text")) file.text = f.at("text").get<std::string>();
      file.hash = f.contains("hash") ? f.at("hash").get<std::string>() : HashText(*file.text);
      snapshot.files.push_back(file);
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

std::vector<std::string> DescribeInputChanges(const InputsSnapshot& a, const InputsSnapshot& b) {
  std::vector<std::string> changes;
  if (a.flight_stack != b.flight_stack) {
    const auto shown = [](const std::string& command) {
      return command.empty() ? std::string("in process") : "'" + command + "'";
    };
    changes.push_back("flight stack: " + shown(a.flight_stack) + " (A) vs " +
                      shown(b.flight_stack) + " (B)");
  }
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
