#pragma once
// The payload reference types and their keys, declared once: the scenario loader reads each
// key with the range and default declared here, and `hpa schema references` prints the table.

#include <optional>
#include <string>
#include <vector>

namespace hpa {

/// One key of a reference type's `reference:` block.
struct ReferenceKey {
  std::string key;
  std::string unit;                // "m", "s", "-" (a number), "" (a file name)
  int size = 1;                    // 1: a number, 3: a vector, 0: text
  double min = 0.0, max = 0.0;     // each element's allowed range
  std::optional<double> fallback;  // the default (every element of a vector); none: required
  std::string meaning;
};

/// One reference type: its name, what it traces (with its formula) and its keys.
struct ReferenceType {
  std::string name;
  std::string description;
  std::vector<ReferenceKey> keys;
};

/// Every reference type, in the order `hpa schema` lists them.
const std::vector<ReferenceType>& ReferenceTypes();

/// The declaration of `key` of reference type `type` (std::out_of_range if there is none).
const ReferenceKey& FindReferenceKey(const std::string& type, const std::string& key);

}  // namespace hpa
