#pragma once
// `hpa schema`: the registries and tables the tools read (controllers, estimators, OCP solvers,
// event types, expect keys, metrics, a scenario's rate table), printed as Markdown from the same
// declarations the loader and the tools use. docs/schema.md is this output (ctest checks it).

#include <string>

namespace hpa {

/// The Markdown of one section ("controllers", "estimators", "solvers", "events", "expect",
/// "metrics", "world") or of all of them ("all"); throws InputError for an unknown section.
std::string SchemaMarkdown(const std::string& section);

/// `hpa schema` entry point; returns the exit code.
int SchemaMain(int argc, char** argv);

}  // namespace hpa
