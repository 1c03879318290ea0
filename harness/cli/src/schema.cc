#include "hpa/scenarios/schema.h"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <map>
#include <sstream>
#include <vector>

#include "hpa/controller/controller_registry.h"
#include "hpa/controller/team_controller.h"
#include "hpa/controller/ocp_solver.h"
#include "hpa/estimator/estimator_registry.h"
#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/scenarios/events.h"
#include "hpa/scenarios/expect_keys.h"
#include "hpa/scenarios/metric_defs.h"
#include "hpa/scenarios/reference_types.h"
#include "hpa/scenarios/runner.h"
#include "hpa/scenarios/scenario.h"
#include "hpa/scenarios/world_profile_yaml.h"
#include "hpa/sim/faults.h"
#include "harness/cli/src/cli_parse.h"

namespace hpa {
namespace {

// A Markdown table: header cells, then rows of the same width.
std::string Table(const std::vector<std::string>& header,
                  const std::vector<std::vector<std::string>>& rows) {
  std::string md = "|";
  for (const std::string& h : header) md += " " + h + " |";
  md += "\n|";
  for (size_t i = 0; i < header.size(); ++i) md += "---|";
  md += "\n";
  for (const auto& row : rows) {
    md += "|";
    for (const std::string& cell : row) md += " " + cell + " |";
    md += "\n";
  }
  return md;
}

// A number as short text ("150", "0.02").
std::string Short(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

std::string BetterText(Better b) {
  switch (b) {
    case Better::kLower:
      return "lower";
    case Better::kHigher:
      return "higher";
    case Better::kNeither:
      break;
  }
  return "-";
}

// The registered controllers with the estimator each flies with.
std::string ControllersSection() {
  std::vector<std::vector<std::string>> rows;
  for (const ControllerRegistration& c : Controllers()) {
    rows.push_back({"`" + c.name + "`", c.estimator, c.description});
  }
  std::vector<std::vector<std::string>> team_rows;
  for (const std::string& name : TeamControllerNames()) {
    team_rows.push_back({"`" + name + "`", TeamControllerDescription(name)});
  }
  return "## Controllers (`controller.type`, `--controller`)\n\n" +
         Table({"name", "estimator", "what it is"}, rows) +
         "\nA team scenario's (`vehicles:`, docs/cooperative.md), one instance per vehicle:\n\n" +
         Table({"name", "what it is"}, team_rows);
}

// The registered estimator variants.
std::string EstimatorsSection() {
  std::vector<std::vector<std::string>> rows;
  for (const EstimatorRegistration& e : Estimators()) {
    rows.push_back({"`" + e.name + "`", e.description});
  }
  return "## Estimators (`estimation.estimator`)\n\n" + Table({"name", "what it is"}, rows);
}

// The registered OCP solvers.
std::string SolversSection() {
  std::vector<std::vector<std::string>> rows;
  for (const OcpSolverRegistration& s : OcpSolvers()) {
    rows.push_back({"`" + s.name + "`", s.description});
  }
  return "## OCP solvers (`controller.solver`)\n\n" + Table({"name", "what it is"}, rows);
}

// The registered event types.
std::string EventsSection() {
  std::vector<std::vector<std::string>> rows;
  for (const EventRegistration& e : EventTypes()) {
    rows.push_back({"`" + e.name + "`", e.description});
  }
  return "## Event types (`events[].type`)\n\n" + Table({"type", "what it does"}, rows);
}

// The fault event's components and modes (sim::FaultComponents), each with its keys.
std::string FaultsSection() {
  std::vector<std::vector<std::string>> rows;
  for (const sim::FaultComponentDecl& c : sim::FaultComponents()) {
    for (const sim::FaultModeDecl& m : c.modes) {
      std::string keys = m.has_duration ? "`duration` s (default: to the end)" : "";
      for (const sim::FaultKeyDecl& k : m.keys) {
        std::ostringstream line;
        line << "`" << k.key << "` " << k.unit << (k.vector != nullptr ? " (3)" : "") << ", "
             << k.min << " to " << k.max;
        if (k.fallback) line << ", default " << *k.fallback;
        line << ": " << k.description;
        keys += (keys.empty() ? "" : "; ") + line.str();
      }
      rows.push_back({"`" + c.name + "`", "`" + m.name + "`", m.px4.empty() ? "-" : m.px4,
                      m.description, keys.empty() ? "-" : keys});
    }
  }
  return "## Faults (`events[]` of `type: fault`)\n\nEvery fault event also takes "
         "`tracking_bound` (m, 0.001 to 10, default 0.1): the payload error its recovery "
         "metrics count as tracking again ([faults.md](faults.md)).\n\n" +
         Table({"component", "mode", "PX4", "what it does", "keys"}, rows);
}

// The expect keys with the metric each bounds, its comparison and unit.
std::string ExpectSection() {
  std::vector<std::vector<std::string>> rows;
  for (const ExpectKey& k : ExpectKeys()) {
    rows.push_back({"`" + k.key + "`", "`" + k.metric + "`", k.comparison, k.unit, k.description});
  }
  return "## Expect keys (`expect:`)\n\n" +
         Table({"key", "metric", "passes when", "unit", "meaning"}, rows);
}

// The metric table: where each metric sits in metrics.json, its unit and how it is compared.
std::string MetricsSection() {
  std::vector<std::vector<std::string>> rows;
  for (const MetricDef& m : MetricDefs()) {
    rows.push_back({"`" + m.name + "`", "`" + m.json_path + "`", m.unit, BetterText(m.better),
                    m.compared ? Short(m.min_effect) : "-", m.timing ? "yes" : "no",
                    m.description});
  }
  return "## Metrics (read from metrics.json by compare, sweep-diff and sweep summaries)\n\n" +
         Table({"name", "metrics.json", "unit", "better", "sweep-diff effect", "timing", "meaning"},
               rows);
}

// Each reference type with a table of its keys (unit, range, default).
std::string ReferencesSection() {
  std::string md = "## Reference types (`reference.type`) and their keys (`reference.KEY`)\n";
  for (const ReferenceType& t : ReferenceTypes()) {
    std::vector<std::vector<std::string>> rows;
    for (const ReferenceKey& k : t.keys) {
      const std::string range =
          k.size == 0 ? "-" : Short(k.min) + " to " + Short(k.max) + (k.size == 3 ? " (3)" : "");
      rows.push_back({"`" + k.key + "`", k.unit.empty() ? "-" : k.unit, range,
                      k.fallback ? Short(*k.fallback) : "required", k.meaning});
    }
    md += "\n### `" + t.name + "`\n\n" + t.description + ".\n\n" +
          Table({"key", "unit", "range", "default", "meaning"}, rows);
  }
  return md;
}

// Every parameter from its declaration (ParamsTables): key, unit, range, models/params.yaml's
// value and meaning, one table per section.
std::string ParamsSection() {
  const Params values = LoadParams(DefaultParamsPath());
  std::string md =
      "## Parameters (`params.SECTION.KEY` in a scenario, params.yaml's keys)\n\n"
      "A scenario's `params:` block (or `--set params.SECTION.KEY=VALUE`, a sweep's "
      "`vary: params.SECTION.KEY`) changes these for the flight code and the world alike, "
      "checked with these ranges (and: k_m / k_f at most 0.2 m, the idle speed below the full "
      "speed, slack_epsilon_m below the cable length, R_BC a rotation, and hover within 80 % of "
      "full thrust); the values are models/params.yaml's.\n";
  for (const ParamTable<Params>& table : ParamsTables()) {
    const std::string prefix = table.section.empty() ? "params." : "params." + table.section + ".";
    md += "\n### `" + (table.section.empty() ? std::string("params") : "params." + table.section) +
          "`: " + table.description + "\n\n" +
          ParamTableMarkdown(table, values, prefix, "params.yaml");
  }
  return md;
}

// Each registered controller's own settings, from its declarations.
std::string ControllerSection() {
  std::string md =
      "## Controller settings (`controller.KEY`)\n\n`type` names a registered controller "
      "(above). Each controller declares the settings it reads; a key another controller "
      "declares is that one's and is left alone (`hpa compare` flies one scenario with several). "
      "`qp_method` is how the `rti` solver solves its QP: `structured` (condensing that skips the "
      "model's zero blocks, then a dense box QP), `dense` (plain condensing, the reference) or "
      "`riccati` (no condensing: an active-set box QP whose subproblems are Riccati recursions); "
      "all three give the same step up to rounding.\n";
  for (const ControllerRegistration& c : Controllers()) {
    md += "\n### `" + c.name + "`\n\n";
    if (c.settings.empty()) {
      md += "No settings.\n";
      continue;
    }
    std::vector<std::vector<std::string>> rows;
    for (const SettingDecl& d : c.settings) {
      std::string range;
      if (std::holds_alternative<double>(d.default_value)) {
        range = SettingText(d.min) + " to " + SettingText(d.max);
      } else if (std::holds_alternative<bool>(d.default_value)) {
        range = "true / false";
      } else if (d.choices) {
        for (const std::string& name : d.choices()) range += (range.empty() ? "" : " / ") + name;
      }
      rows.push_back({"`controller." + d.key + "`", d.unit, range, SettingText(d.default_value),
                      d.description});
    }
    md += Table({"key", "unit", "range", "default", "meaning"}, rows);
  }
  return md;
}

// The world-profile keys with the flight profile's values.
std::string WorldSection() {
  return "## World profile keys (`world.SECTION.KEY`, with the `flight` profile's values)\n\n"
         "Any key can be set in a scenario's `world:` block or with `--set`; `ideal` switches "
         "every part off.\n" +
         WorldProfileMarkdown("flight");
}

// One section of the schema by name; InputError naming the valid ones for any other.
std::string Section(const std::string& section) {
  static const std::map<std::string, std::string (*)()> kSections = {
      {"controllers", &ControllersSection}, {"estimators", &EstimatorsSection},
      {"solvers", &SolversSection},         {"events", &EventsSection},
      {"expect", &ExpectSection},           {"metrics", &MetricsSection},
      {"references", &ReferencesSection},   {"params", &ParamsSection},
      {"controller", &ControllerSection},   {"world", &WorldSection},
      {"faults", &FaultsSection}};
  const auto it = kSections.find(section);
  if (it != kSections.end()) return it->second();
  throw InputError("", "schema",
                   "unknown section '" + section +
                       "' (expected all, controllers, estimators, solvers, controller, events, "
                       "faults, expect, metrics, world, references, params or rates)");
}

}  // namespace

std::string SchemaMarkdown(const std::string& section) {
  if (section != "all") return Section(section);
  std::string md =
      "# Schema\n\nGenerated by `hpa schema all` from the registries the loader and the tools "
      "read; do not edit by hand (ctest `cli.schema_docs` compares it with the binary's "
      "output). The rate table of a scenario: `hpa schema rates SCENARIO.yaml`.\n";
  for (const char* s : {"controllers", "estimators", "solvers", "controller", "references",
                        "params", "events", "faults", "expect", "metrics", "world"}) {
    md += "\n" + Section(s);
  }
  return md;
}

int SchemaMain(int argc, char** argv) {
  std::string section = "all", scenario_file;
  CLI::App app{
      "Prints, as Markdown, what the tools accept and measure: controllers, estimators, solvers, "
      "reference types and their keys, params, event types, expect keys, metrics, world-profile "
      "keys (from their registries and "
      "declared parameter tables), or a scenario's rate table "
      "(every loop and stream with its rate and latency, as a run uses them).",
      "hpa schema"};
  app.add_option(
         "SECTION", section,
         "all | controllers | estimators | solvers | controller | references | params | events | "
         "expect | metrics | world | rates")
      ->capture_default_str();
  app.add_option("SCENARIO.yaml", scenario_file, "with rates: the scenario");
  if (const auto code = ParseCommandLine(app, argc, argv)) return *code;
  if (section == "rates") {
    if (scenario_file.empty()) throw InputError("", "schema rates", "needs a SCENARIO.yaml");
    const Scenario scenario = LoadScenario(scenario_file);
    std::vector<std::vector<std::string>> rows;
    for (const RateRow& r : ScenarioRateTable(scenario, LoadParams(DefaultParamsPath()))) {
      rows.push_back({r.name, r.rate_hz > 0 ? Short(r.rate_hz) : "-", Short(r.latency_s * 1e3),
                      r.noise.empty() ? "-" : r.noise, r.from});
    }
    std::fputs(
        ("## Rates of " + scenario.name + " (world profile " + scenario.world.name + ")\n\n" +
         Table({"loop or stream", "rate [Hz]", "latency [ms]", "noise", "set by"}, rows))
            .c_str(),
        stdout);
    return 0;
  }
  if (!scenario_file.empty()) {
    throw InputError("", scenario_file, "a scenario file goes with `hpa schema rates` only");
  }
  std::fputs(SchemaMarkdown(section).c_str(), stdout);
  return 0;
}

}  // namespace hpa
