#include "hpa/models/yaml_reader.h"

#include <yaml-cpp/eventhandler.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"

namespace hpa {
namespace {

// Numbers in messages: whole numbers in full (a seed bound of 4294967295, not 4.29497e+09),
// others with the digits that tell them apart.
std::string Range(double min, double max) {
  std::ostringstream out;
  out.precision(15);
  out << "[" << min << ", " << max << "]";
  return out.str();
}

// A quoted scalar ('5', "true") or a tagged one (!!str 2, !foo 1) is a string: yaml-cpp would
// still convert it to a number or a bool. Plain scalars carry the non-specific tag "?", quoted
// ones "!", tagged ones their tag (nodes built in code: "").
bool Quoted(const YAML::Node& n) { return n.IsScalar() && !n.Tag().empty() && n.Tag() != "?"; }

// Why a scalar that is not plain is refused where a number or a bool is expected.
std::string NotPlain(const YAML::Node& n) {
  if (n.Tag() == "!") return ", got a quoted string (remove the quotes)";
  return ", got a scalar tagged '" + n.Tag() + "' (write a plain value, no tag)";
}

}  // namespace

YamlMap::YamlMap(YAML::Node node, std::string file, std::string path)
    : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {
  if (!node_.IsMap()) {
    throw InputError(file_, path_, "expected a map of keys");
  }
  // every key a plain scalar, each once: yaml-cpp keeps complex keys (`? [a]: 1`) and lets the
  // first of two equal keys win silently
  std::set<std::string> seen;
  for (const auto& kv : node_) {
    if (!kv.first.IsScalar()) {
      throw InputError(file_, path_, "a key must be a plain name, not a list or map");
    }
    const std::string key = kv.first.Scalar();
    if (!seen.insert(key).second) throw InputError(file_, KeyPath(key), "duplicate key");
  }
}

namespace {

// Parser events ignored: only how many documents the text holds matters.
class DocumentCounter final : public YAML::EventHandler {
 public:
  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t,
                const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}
};

}  // namespace

YAML::Node LoadYamlText(const std::string& text, const std::string& file) {
  try {
    // one document: YAML::Load reads the first and ignores the rest silently. A second is
    // looked for one document at a time (YAML::LoadAll loops forever on some malformed texts,
    // e.g. a stray '}' after the first document)
    std::istringstream in(text);
    YAML::Parser parser(in);
    DocumentCounter counter;
    if (parser.HandleNextDocument(counter) && parser.HandleNextDocument(counter)) {
      throw InputError(file, "",
                       "holds more than one YAML document (a '---', or text after the first "
                       "document ends); expected one");
    }
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError(file, "", std::string("malformed YAML: ") + e.what());
  }
}

std::string ReadYamlFile(const std::string& file) {
  // YAML files are small: 16 MiB is far above any scenario, params or sweep file
  return ReadInputFile(file, "a YAML file", std::uintmax_t{16} << 20);
}

YAML::Node LoadYamlFile(const std::string& file) { return LoadYamlText(ReadYamlFile(file), file); }

YamlMap YamlMap::LoadFile(const std::string& file) {
  const YAML::Node root = LoadYamlFile(file);
  if (!root.IsMap()) throw InputError(file, "", "expected a YAML map at the top level");
  return YamlMap(root, file, "");
}

std::string YamlMap::KeyPath(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

void YamlMap::Fail(const std::string& key, const std::string& what) const {
  throw InputError(file_, KeyPath(key), what);
}

bool YamlMap::Has(const std::string& key) const {
  asked_.insert(key);
  return static_cast<bool>(node_[key]);
}

YAML::Node YamlMap::Get(const std::string& key) const {
  asked_.insert(key);
  YAML::Node n = node_[key];
  if (!n) Fail(key, "missing required key");
  read_.insert(key);
  return n;
}

double YamlMap::Number(const std::string& key, double min, double max) const {
  YAML::Node n = Get(key);
  double v = 0.0;
  try {
    if (!n.IsScalar() || Quoted(n)) throw YAML::Exception(YAML::Mark(), "");
    v = n.as<double>();
  } catch (const YAML::Exception&) {
    Fail(key, "expected a number in " + Range(min, max) + (Quoted(n) ? NotPlain(n) : ""));
  }
  if (!std::isfinite(v) || v < min || v > max) {
    std::ostringstream out;
    out.precision(15);
    out << "value " << v << " out of range, expected a number in " << Range(min, max);
    Fail(key, out.str());
  }
  return v;
}

double YamlMap::Number(const std::string& key, double min, double max, double fallback) const {
  return Has(key) ? Number(key, min, max) : fallback;
}

long YamlMap::Integer(const std::string& key, long min, long max) const {
  const double v = Number(key, static_cast<double>(min), static_cast<double>(max));
  if (v != std::floor(v)) Fail(key, "expected an integer in " + Range(min, max));
  return static_cast<long>(v);
}

long YamlMap::Integer(const std::string& key, long min, long max, long fallback) const {
  return Has(key) ? Integer(key, min, max) : fallback;
}

bool YamlMap::Bool(const std::string& key, bool fallback) const {
  if (!Has(key)) return fallback;
  YAML::Node n = Get(key);
  try {
    if (Quoted(n)) throw YAML::Exception(YAML::Mark(), "");
    return n.as<bool>();
  } catch (const YAML::Exception&) {
    Fail(key, std::string("expected true or false") + (Quoted(n) ? NotPlain(n) : ""));
  }
}

std::string YamlMap::String(const std::string& key) const {
  YAML::Node n = Get(key);
  if (!n.IsScalar()) Fail(key, "expected a string");
  return n.as<std::string>();
}

std::string YamlMap::String(const std::string& key, const std::string& fallback) const {
  return Has(key) ? String(key) : fallback;
}

std::string YamlMap::Choice(const std::string& key, const std::vector<std::string>& allowed,
                            const std::string& fallback) const {
  const std::string v = String(key, fallback);
  for (const auto& a : allowed) {
    if (v == a) return v;
  }
  std::string list;
  for (const auto& a : allowed) list += (list.empty() ? "" : " | ") + a;
  Fail(key, "unknown value '" + v + "', expected one of: " + list);
}

Eigen::VectorXd YamlMap::Vector(const std::string& key, int size, double min, double max) const {
  YAML::Node n = Get(key);
  std::ostringstream expect;
  expect << "expected a list of " << size << " numbers in " << Range(min, max);
  if (!n.IsSequence() || static_cast<int>(n.size()) != size) Fail(key, expect.str());
  Eigen::VectorXd v(size);
  for (int i = 0; i < size; ++i) {
    try {
      if (Quoted(n[i])) throw YAML::Exception(YAML::Mark(), "");
      v(i) = n[i].as<double>();
    } catch (const YAML::Exception&) {
      Fail(key, expect.str());
    }
    if (!std::isfinite(v(i)) || v(i) < min || v(i) > max) Fail(key, expect.str());
  }
  return v;
}

YamlMap YamlMap::Map(const std::string& key) const {
  YAML::Node n = Get(key);
  if (!n.IsMap()) Fail(key, "expected a map of keys");
  return YamlMap(n, file_, KeyPath(key));
}

YAML::Node YamlMap::Node(const std::string& key) const { return Get(key); }

void YamlMap::RejectUnknownKeys() const {
  for (const auto& kv : node_) {
    const std::string key = kv.first.Scalar();
    if (read_.count(key) != 0) continue;
    std::string valid;
    for (const std::string& k : asked_) valid += (valid.empty() ? "" : ", ") + k;
    Fail(key, "unknown key" + (valid.empty() ? std::string() : "; valid keys here: " + valid));
  }
}

}  // namespace hpa

namespace hpa {

Eigen::Matrix3d ReadMatrix3(const YamlMap& map, const std::string& key, double min, double max) {
  const YAML::Node rows = map.Node(key);
  const std::string expect =
      "expected a 3x3 matrix as a list of 3 rows of 3 numbers in " + Range(min, max);
  if (!rows.IsSequence() || rows.size() != 3) map.Fail(key, expect);
  Eigen::Matrix3d m;
  for (int i = 0; i < 3; ++i) {
    if (!rows[i].IsSequence() || rows[i].size() != 3) map.Fail(key, expect);
    for (int j = 0; j < 3; ++j) {
      try {
        if (Quoted(rows[i][j])) throw YAML::Exception(YAML::Mark(), "");
        m(i, j) = rows[i][j].as<double>();
      } catch (const YAML::Exception&) {
        map.Fail(key, expect);
      }
      if (!std::isfinite(m(i, j)) || m(i, j) < min || m(i, j) > max) map.Fail(key, expect);
    }
  }
  return m;
}

}  // namespace hpa
