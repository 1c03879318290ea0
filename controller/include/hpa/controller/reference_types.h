#pragma once
// The payload reference types, one registry (models/registry.h): each type declares its keys
// (unit, range, default) and carries its behaviour: how its `reference:` block's key values
// become a ReferenceSpec, where the payload RMSE starts, and the trajectory generator it flies.
// Flight code: an external flight stack receives the spec over the lockstep protocol and builds
// the generator from it. A new type is its own file in controller/src/ plus one line in
// reference_types.cc, or a RegisterReferenceType call from a test or plugin.

#include <Eigen/Core>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hpa/controller/reference.h"
#include "hpa/controller/reference_spec.h"
#include "hpa/models/params.h"

namespace hpa {

/// The range of every coordinate of a reference position (world, m): far beyond the 20 m arena,
/// only a guard against typos. Every position key and a CSV's samples share it.
constexpr double kReferencePositionBound_m = 1e3;

/// One key of a reference type's `reference:` block.
struct ReferenceKey {
  std::string key;
  std::string unit;                // "m", "s", "-" (a number), "" (a file name)
  int size = 1;                    // 1: a number, 3: a vector, 0: a file name (text)
  double min = 0.0, max = 0.0;     // each element's allowed range
  std::optional<double> fallback;  // the default (every element of a vector); none: required
  std::string meaning;
};

/// The values of a reference block's keys, as its type's key table declares them (defaults
/// filled in): what a type's `read` turns into a ReferenceSpec.
struct ReferenceKeyValues {
  std::map<std::string, std::vector<double>> numbers;  // each number (1) or vector (3) key
  std::map<std::string, std::string> files;  // each file key: its path, as the loader resolved it
  std::optional<std::string> file_text;      // the file's text from a snapshot (run.json), if any

  /// The number `key` (std::out_of_range if the block has no such number key).
  double Number(const std::string& key) const;
  /// The 3-vector `key` (std::out_of_range if the block has no such vector key).
  Eigen::Vector3d Vector3(const std::string& key) const;
  /// The file path `key` (std::out_of_range if the block has no such file key).
  const std::string& File(const std::string& key) const;
};

/// Fills a spec's fields from its block's key values (the spec's type and file already set).
using ReferenceReader = std::function<void(const ReferenceKeyValues&, ReferenceSpec*)>;
/// Where the payload RMSE of a spec starts (s): the end of a ramp-up, 0 for one flown at once.
using ReferenceRmseStart = std::function<double(const ReferenceSpec&)>;
/// Builds the trajectory generator a spec describes, for the flight params.
using ReferenceFactory =
    std::function<std::shared_ptr<Reference>(const ReferenceSpec&, const Params&)>;

/// One reference type: its name, what it traces (with its formula), its keys and its behaviour.
/// A type reads at most one file (its one size-0 key): its path is ReferenceSpec::file, which a
/// run's record snapshots.
struct ReferenceType {
  std::string name;  // as written in scenarios (reference.type)
  std::string description;
  std::vector<ReferenceKey> keys;
  ReferenceReader read;            // unset: the spec keeps the numbers as read (spec.values)
  ReferenceRmseStart rmse_from_s;  // required
  ReferenceFactory make;           // required
};

/// Every reference type, in registration order (built-ins first: the order `hpa schema` lists).
const std::vector<ReferenceType>& ReferenceTypes();

/// The type called `name`, or nullptr.
const ReferenceType* FindReferenceType(const std::string& name);

/// The type of a spec; throws std::invalid_argument naming the known types if it has none.
const ReferenceType& ReferenceTypeOf(const ReferenceSpec& spec);

/// The names of every reference type, in order.
std::vector<std::string> ReferenceTypeNames();

/// Adds a reference type at run time (tests, plugins); throws std::invalid_argument on an empty
/// or duplicate name, a missing factory or RMSE start, or more than one file key.
void RegisterReferenceType(ReferenceType type);

/// The declaration of `key` of reference type `type` (std::out_of_range if there is none).
const ReferenceKey& FindReferenceKey(const std::string& type, const std::string& key);

/// The file key of `type` (the one of size 0), or nullptr if it reads no file.
const ReferenceKey* FileKeyOf(const ReferenceType& type);

/// Builds a spec of `type` from its key values: the spec's file from the file key, then the
/// type's read (or the numbers kept as read). The scenario loader and tests call it.
ReferenceSpec ReadReferenceSpec(const ReferenceType& type, const ReferenceKeyValues& values);

/// Why `spec.values` does not fit its type's key table (a key it does not declare, a wrong
/// size, a value outside the declared range), or nullopt when it fits: the check a spec received
/// over the protocol passes.
std::optional<std::string> ReferenceValuesError(const ReferenceSpec& spec);

}  // namespace hpa
