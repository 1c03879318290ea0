#include "hpa/controller/reference_types.h"

#include <stdexcept>
#include <utility>

#include "hpa/models/registry.h"

namespace hpa {

// The built-in reference types, each defined in its own file.
ReferenceType HoverReferenceType();
ReferenceType LissajousReferenceType();
ReferenceType LineReferenceType();
ReferenceType CircleReferenceType();
ReferenceType FigureEightReferenceType();
ReferenceType CsvReferenceType();

namespace {

// `type` itself; throws std::invalid_argument for what the registry template does not check:
// a missing RMSE start, or more than one file key (ReferenceSpec holds one file).
ReferenceType Checked(ReferenceType type) {
  if (!type.rmse_from_s) {
    throw std::invalid_argument("register reference type: '" + type.name +
                                "' has no RMSE start (rmse_from_s)");
  }
  int files = 0;
  for (const ReferenceKey& k : type.keys) files += k.size == 0 ? 1 : 0;
  if (files > 1) {
    throw std::invalid_argument("register reference type: '" + type.name +
                                "' has more than one file key");
  }
  return type;
}

// The built-in types, one line each, in the order `hpa schema` lists them.
Registry<ReferenceType>& TheRegistry() {
  static Registry<ReferenceType> registry(
      "reference type",
      {
          Checked(HoverReferenceType()),
          Checked(LissajousReferenceType()),
          Checked(LineReferenceType()),
          Checked(CircleReferenceType()),
          Checked(FigureEightReferenceType()),
          Checked(CsvReferenceType()),
      });
  return registry;
}

// The element `key` of `map`, or std::out_of_range naming what and which key.
template <typename Map>
const typename Map::mapped_type& At(const Map& map, const std::string& key, const char* what) {
  const auto it = map.find(key);
  if (it == map.end()) throw std::out_of_range(std::string("no reference ") + what + " " + key);
  return it->second;
}

}  // namespace

double ReferenceKeyValues::Number(const std::string& key) const {
  const std::vector<double>& v = At(numbers, key, "number");
  if (v.size() != 1) throw std::out_of_range("reference key " + key + " is not a number");
  return v[0];
}

Eigen::Vector3d ReferenceKeyValues::Vector3(const std::string& key) const {
  const std::vector<double>& v = At(numbers, key, "vector");
  if (v.size() != 3) throw std::out_of_range("reference key " + key + " is not a 3-vector");
  return {v[0], v[1], v[2]};
}

const std::string& ReferenceKeyValues::File(const std::string& key) const {
  return At(files, key, "file");
}

const std::vector<ReferenceType>& ReferenceTypes() { return TheRegistry().All(); }

const ReferenceType* FindReferenceType(const std::string& name) {
  return TheRegistry().Find(name);
}

const ReferenceType& ReferenceTypeOf(const ReferenceSpec& spec) {
  return TheRegistry().Get(spec.type, "reference.type");
}

std::vector<std::string> ReferenceTypeNames() { return TheRegistry().Names(); }

void RegisterReferenceType(ReferenceType type) { TheRegistry().Add(Checked(std::move(type))); }

const ReferenceKey& FindReferenceKey(const std::string& type, const std::string& key) {
  if (const ReferenceType* t = FindReferenceType(type)) {
    for (const ReferenceKey& k : t->keys) {
      if (k.key == key) return k;
    }
  }
  throw std::out_of_range("no reference key " + type + "." + key);
}

const ReferenceKey* FileKeyOf(const ReferenceType& type) {
  for (const ReferenceKey& k : type.keys) {
    if (k.size == 0) return &k;
  }
  return nullptr;
}

ReferenceSpec ReadReferenceSpec(const ReferenceType& type, const ReferenceKeyValues& values) {
  ReferenceSpec spec;
  spec.type = type.name;
  if (const ReferenceKey* file = FileKeyOf(type)) spec.file = values.File(file->key);
  if (type.read) {
    type.read(values, &spec);
  } else {
    spec.values = values.numbers;
  }
  return spec;
}

std::optional<std::string> ReferenceValuesError(const ReferenceSpec& spec) {
  const ReferenceType* type = FindReferenceType(spec.type);
  if (type == nullptr) return "unknown reference type '" + spec.type + "'";
  if (type->read) {
    // a type with a read of its own keeps its values in the spec's fields
    if (!spec.values.empty()) return spec.type + " keeps no key values";
    return std::nullopt;
  }
  for (const ReferenceKey& k : type->keys) {
    if (k.size > 0 && spec.values.count(k.key) == 0) return k.key + ": missing";
  }
  for (const auto& [key, numbers] : spec.values) {
    const ReferenceKey* declared = nullptr;
    for (const ReferenceKey& k : type->keys) {
      if (k.key == key && k.size > 0) declared = &k;
    }
    if (declared == nullptr) return spec.type + " has no number or vector key '" + key + "'";
    if (numbers.size() != static_cast<size_t>(declared->size)) {
      return key + ": expected " + std::to_string(declared->size) + " numbers";
    }
    for (double v : numbers) {
      if (!(v >= declared->min && v <= declared->max)) {
        return key + ": " + std::to_string(v) + " outside " + std::to_string(declared->min) +
               " to " + std::to_string(declared->max);
      }
    }
  }
  return std::nullopt;
}

}  // namespace hpa
