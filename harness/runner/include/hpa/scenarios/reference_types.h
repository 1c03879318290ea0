#pragma once
// The scenario side of the payload reference types (controller/reference_types.h declares them,
// with their keys and behaviour): a scenario's `reference:` block read as its type's key table
// says, each key with its declared range and default; `hpa schema references` prints the table.

#include <optional>
#include <string>

#include "hpa/controller/reference_types.h"
#include "hpa/models/yaml_reader.h"

namespace hpa {

/// The spec a scenario's `reference:` block describes: `type` (default hover) chosen among the
/// registered types, each of its keys read with its declared range and default (a file key
/// relative to the scenario file), then the type's read; unknown keys are refused.
/// `file_text`, when given, is the text of the type's file (a run.json's snapshot), read in
/// place of the file. Throws InputError naming the file and key.
ReferenceSpec ParseReferenceBlock(const YamlMap& block,
                                  const std::optional<std::string>& file_text);

}  // namespace hpa
