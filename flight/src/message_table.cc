#include "message_table.h"

#include <cstdio>
#include <cstring>
#include <set>

namespace hpa::flight::wire {
namespace {

static_assert(sizeof(double) == 8, "the protocol's numbers are IEEE doubles");

// python/hpa_sim/messages.json, as flight/CMakeLists.txt wrote it into a raw string literal
constexpr char kMessagesJson[] =
#include "messages_json.inc"
    ;

// The keys a field of the table may have (a misspelt key is an error, not ignored).
const std::set<std::string> kFieldKeys = {
    "name",    "label", "type",   "unit",    "count",
    "list",    "item",  "values", "bits",    "present_if",
    "finite",  "min",   "max",    "refused", "unit_quaternion",
    "default", "doc"};

[[noreturn]] void Inconsistent(const std::string& where, const std::string& what) {
  throw std::logic_error("messages.json: " + where + ": " + what);
}

}  // namespace

std::string Format(std::string text, const Vars& vars) {
  for (const auto& [name, value] : vars) {
    const std::string key = "{" + name + "}";
    for (size_t at = text.find(key); at != std::string::npos;
         at = text.find(key, at + value.size())) {
      text.replace(at, key.size(), value);
    }
  }
  return text;
}

std::string ShownValue(double v) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

std::string ShownLimit(double v) {
  char text[40];
  std::snprintf(text, sizeof text, "%.15g", v);
  return text;
}

std::string In(const std::string& at) { return at.empty() ? "" : at + " "; }

std::string Of(const std::string& at) { return at.empty() ? "" : at + "'s "; }

const Table& Table::Get() {
  static const Table table;
  return table;
}

Table::Table() : json_(nlohmann::json::parse(kMessagesJson)) {
  // protocol.h's compile-time constants are the table's
  if (json_.at("protocol_version") != kProtocolVersion || json_.at("magic") != kMagic ||
      json_.at("max_message_bytes") != kMaxMessageBytes) {
    Inconsistent("framing", "protocol_version, magic or max_message_bytes differ from protocol.h");
  }
  for (const nlohmann::json& type : json_.at("message_types")) {
    const std::string& name = type.at("name").get_ref<const std::string&>();
    if (MessageTypeName(static_cast<MessageType>(type.at("id").get<uint32_t>())) != name) {
      Inconsistent("message_types", name + "'s id differs from protocol.h's MessageType");
    }
    if (type.contains("layout")) Resolve(type.at("layout").get<std::string>());
    if (type.at("encoding") == "json") CheckKeyDeclarations(type.at("keys"), name);
  }
  for (const auto& item : json_.at("structs").items()) Resolve(item.key());
}

void Table::CheckKeyDeclarations(const nlohmann::json& keys, const std::string& where) {
  static const std::set<std::string> kTypes = {"integer", "number", "string",
                                               "bool",    "object", "array"};
  static const std::set<std::string> kKeyKeys = {"name", "type", "required", "keys", "doc"};
  std::set<std::string> names;
  for (const nlohmann::json& k : keys) {
    for (const auto& item : k.items()) {
      if (kKeyKeys.count(item.key()) == 0) Inconsistent(where, "unknown key " + item.key());
    }
    const std::string name = k.at("name").get<std::string>();
    if (!names.insert(name).second) Inconsistent(where + "." + name, "declared twice");
    if (kTypes.count(k.at("type").get<std::string>()) == 0) {
      Inconsistent(where + "." + name, "unknown type " + k.at("type").get<std::string>());
    }
    if (!k.contains("doc")) Inconsistent(where + "." + name, "no doc");
    if (k.contains("keys")) {
      if (k.at("type") != "object") Inconsistent(where + "." + name, "keys of a non-object");
      CheckKeyDeclarations(k.at("keys"), where + "." + name);
    }
  }
}

const Struct& Table::Find(const std::string& name) const {
  const auto it = structs_.find(name);
  if (it == structs_.end()) Inconsistent("structs", "no struct named " + name);
  return it->second;
}

std::string Table::Error(const std::string& key, const Vars& vars) const {
  return Format(json_.at("errors").at(key).get<std::string>(), vars);
}

const Struct& Table::Resolve(const std::string& name) {
  const auto done = structs_.find(name);
  if (done != structs_.end()) return done->second;
  if (resolving_[name]) Inconsistent(name, "contains itself");
  resolving_[name] = true;
  const nlohmann::json& j = json_.at("structs").at(name);
  if (!j.contains("doc")) Inconsistent(name, "no doc");
  Struct s;
  s.name = name;
  std::map<std::string, uint32_t> bits;  // bits of the flags fields so far, by name
  for (const nlohmann::json& fj : j.at("fields")) {
    Field f = ParseField(fj, name);
    if (fj.contains("present_if")) {
      const auto bit = bits.find(fj.at("present_if").get<std::string>());
      if (bit == bits.end()) Inconsistent(name + "." + f.name, "present_if names no earlier bit");
      f.gate = bit->second;
    }
    for (const Bit& b : f.bits) bits[b.name] = b.value;
    if (f.gate == 0) s.min_bytes += f.min_bytes;
    s.fields.push_back(std::move(f));
  }
  resolving_[name] = false;
  return structs_.emplace(name, std::move(s)).first->second;
}

Field Table::ParseField(const nlohmann::json& j, const std::string& where) {
  Field f;
  f.name = j.at("name").get<std::string>();
  const std::string at = where + "." + f.name;
  for (const auto& item : j.items()) {
    if (kFieldKeys.count(item.key()) == 0) Inconsistent(at, "unknown key " + item.key());
  }
  if (!j.contains("doc")) Inconsistent(at, "no doc");
  f.label = j.value("label", f.name);
  f.unit = j.value("unit", "");
  f.count = j.value("count", 1);
  f.list = j.value("list", false);
  f.item = j.value("item", f.name);
  // a named type of "types" refines its base type with checks
  std::string type = j.at("type").get<std::string>();
  nlohmann::json checks = j;
  const nlohmann::json& types = json_.at("types");
  if (types.contains(type) && types.at(type).contains("base")) {
    for (const auto& item : types.at(type).items()) {
      if (!checks.contains(item.key())) checks[item.key()] = item.value();
    }
    type = types.at(type).at("base").get<std::string>();
  }
  static const std::map<std::string, Kind> kinds = {
      {"f64", Kind::kF64},   {"u32", Kind::kU32},     {"i32", Kind::kI32},  {"bool", Kind::kBool},
      {"enum", Kind::kEnum}, {"flags", Kind::kFlags}, {"text", Kind::kText}};
  const auto kind = kinds.find(type);
  if (kind != kinds.end()) {
    f.kind = kind->second;
  } else if (json_.at("structs").contains(type)) {
    f.kind = Kind::kStruct;
    f.type = &Resolve(type);
  } else {
    Inconsistent(at, "unknown type " + type);
  }
  if (f.kind == Kind::kEnum) f.values = j.at("values").get<std::vector<std::string>>();
  if (f.kind == Kind::kFlags) {
    for (const nlohmann::json& bj : j.at("bits")) {
      Bit b;
      b.name = bj.at("name").get<std::string>();
      b.label = bj.value("label", b.name);
      b.value = bj.at("value").get<uint32_t>();
      b.refused = bj.value("refused", "");
      if (!bj.contains("doc")) Inconsistent(at + "." + b.name, "no doc");
      f.bits.push_back(b);
    }
    for (size_t i = 0; i < f.bits.size(); ++i) {
      const nlohmann::json& bj = j.at("bits")[i];
      if (!bj.contains("requires")) continue;
      for (const Bit& other : f.bits) {
        if (other.name == bj.at("requires")) f.bits[i].requires = other.value;
      }
      if (f.bits[i].requires == 0 || f.bits[i].refused.empty()) {
        Inconsistent(at + "." + f.bits[i].name, "requires no bit of its field, or no refused");
      }
    }
  }
  f.finite = checks.value("finite", false);
  if (checks.contains("min")) f.min = checks.at("min").get<double>();
  if (checks.contains("max")) f.max = checks.at("max").get<double>();
  f.refused = checks.value("refused", "");
  if ((f.finite || f.min || f.max) && f.refused.empty()) Inconsistent(at, "a check but no refused");
  if (j.contains("unit_quaternion")) {
    const nlohmann::json& q = j.at("unit_quaternion");
    f.unit_quaternion =
        UnitQuaternion{q.at("field").get<std::string>(), q.at("min_norm"), q.at("max_norm"),
                       q.at("renormalise_beyond"), q.at("refused").get<std::string>()};
  }
  // its smallest encoding
  if (f.list || f.kind == Kind::kText) {
    f.min_bytes = 4;
  } else if (f.kind == Kind::kStruct) {
    f.min_bytes = f.type->min_bytes;
  } else {
    f.min_bytes = static_cast<size_t>(f.count) * (f.kind == Kind::kF64 ? 8 : 4);
  }
  return f;
}

void Writer::Text(const std::string& s) {
  U32(static_cast<uint32_t>(s.size()));
  Raw(s.data(), s.size());
}

void Writer::Raw(const void* p, size_t n) {
  const auto* b = static_cast<const uint8_t*>(p);
  bytes.insert(bytes.end(), b, b + n);
}

double Reader::F64() {
  double v;
  Raw(&v, 8);
  return v;
}

uint32_t Reader::U32() {
  uint32_t v;
  Raw(&v, 4);
  return v;
}

std::string Reader::Text(const Field& f, const std::string& at) {
  const uint32_t n = U32();
  if (n > bytes_.size() - pos_) {
    Fail(Table::Get().Error("text_too_long",
                            {{"of", Of(at)}, {"label", f.label}, {"value", std::to_string(n)}}));
  }
  std::string s(reinterpret_cast<const char*>(bytes_.data() + pos_), n);
  pos_ += n;
  const std::string clean = CleanUtf8(s);
  if (clean != s) {
    // CleanUtf8 copies the text up to its first ill-formed byte
    const size_t bad = static_cast<size_t>(
        std::mismatch(s.begin(), s.end(), clean.begin(), clean.end()).first - s.begin());
    char why[40];
    std::snprintf(why, sizeof why, "byte %zu of it, 0x%02x", bad,
                  static_cast<unsigned>(static_cast<unsigned char>(s[bad])));
    Fail(Table::Get().Error("text_not_utf8", {{"of", Of(at)}, {"label", f.label}, {"why", why}}));
  }
  return s;
}

uint32_t Reader::Count(const Field& f) {
  const uint32_t n = U32();
  const size_t item_bytes = std::max<size_t>(f.type->min_bytes, 1);
  if (static_cast<uint64_t>(n) * item_bytes > bytes_.size() - pos_) {
    Fail(Table::Get().Error("list_too_long", {{"label", f.label}, {"value", std::to_string(n)}}));
  }
  return n;
}

void Reader::End() {
  if (pos_ != bytes_.size()) {
    Fail(Table::Get().Error("trailing", {{"value", std::to_string(bytes_.size() - pos_)}}));
  }
}

void Reader::Fail(const std::string& what) const {
  throw ProtocolError(Table::Get().Error("malformed", {{"message", message_}, {"what", what}}));
}

void Reader::Raw(void* p, size_t n) {
  if (n > bytes_.size() - pos_) {
    Fail(Table::Get().Error("ends_early", {{"pos", std::to_string(pos_)},
                                           {"size", std::to_string(bytes_.size())},
                                           {"need", std::to_string(n)}}));
  }
  std::memcpy(p, bytes_.data() + pos_, n);
  pos_ += n;
}

void CheckNumber(const Reader& r, const Field& f, const std::string& at, double v) {
  if ((f.finite && !std::isfinite(v)) || (f.min && !(v >= *f.min)) || (f.max && !(v <= *f.max))) {
    r.Fail(Format(f.refused, {{"in", In(at)},
                              {"label", f.label},
                              {"value", ShownValue(v)},
                              {"min", f.min ? ShownLimit(*f.min) : ""},
                              {"max", f.max ? ShownLimit(*f.max) : ""}}));
  }
}

void CheckFlags(const Reader& r, const Field& f, const std::string& at, uint32_t flags) {
  char shown[16];
  std::snprintf(shown, sizeof shown, "0x%x", flags);
  uint32_t known = 0;
  std::string choices;
  for (const Bit& b : f.bits) {
    known |= b.value;
    choices += (choices.empty() ? "" : ", ") + std::to_string(b.value) + " " + b.label;
  }
  if ((flags & ~known) != 0) {
    r.Fail(Table::Get().Error(
        "unknown_bits",
        {{"in", In(at)}, {"label", f.label}, {"value", shown}, {"choices", choices}}));
  }
  for (const Bit& b : f.bits) {
    if ((flags & b.value) != 0 && b.requires != 0 && (flags & b.requires) == 0) {
      r.Fail(Format(b.refused, {{"in", In(at)}, {"label", f.label}, {"value", shown}}));
    }
  }
}

namespace detail {

void WrongType(const Field& f, const char* cpp) {
  throw std::logic_error("messages.json's field " + f.name +
                         " does not fit the C++ member bound to it (" + cpp + ")");
}

}  // namespace detail

}  // namespace hpa::flight::wire
