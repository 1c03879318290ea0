// The flight config as JSON (the hello's "config"): what hpa-flight needs to build the flight
// stack the runner would (params, controller, estimator, reference, initial state).

#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "hpa/autopilot/px4_rate_controller.h"
#include "hpa/controller/controller_registry.h"
#include "hpa/controller/reference_types.h"
#include "hpa/flight/protocol.h"

namespace hpa::flight {
namespace {

// The controller block: its type, then every setting the type declares (the value the scenario
// wrote, or the default) as a number, a boolean or a name.
nlohmann::json ControllerToJson(const ControllerConfig& c) {
  nlohmann::json out = {{"type", c.type}};
  const ControllerRegistration* registration = FindController(c.type);
  if (registration == nullptr) return out;
  for (const SettingDecl& d : registration->settings) {
    std::visit([&](const auto& v) { out[d.key] = v; }, SettingOr(c.settings, d));
  }
  return out;
}

// ControllerToJson's block read back: each setting the type declares, checked against its
// declaration (absent: its default, as from a stack of an older version); throws ProtocolError
// naming controller.key.
ControllerConfig ControllerFromJson(const nlohmann::json& j) {
  ControllerConfig c;
  c.type = j.at("type").get<std::string>();
  const ControllerRegistration* registration = FindController(c.type);
  if (registration == nullptr) return c;  // MakeController names the unknown type
  for (const SettingDecl& d : registration->settings) {
    if (!j.contains(d.key)) continue;
    const nlohmann::json& v = j.at(d.key);
    SettingValue value;
    if (v.is_boolean()) {
      value = v.get<bool>();
    } else if (v.is_number()) {
      value = v.get<double>();
    } else if (v.is_string()) {
      value = v.get<std::string>();
    } else {
      throw ProtocolError("controller." + d.key + ": expected a number, a boolean or a name");
    }
    try {
      CheckSetting(d, value, "controller.");
    } catch (const std::invalid_argument& e) {
      throw ProtocolError(e.what());
    }
    c.settings[d.key] = value;
  }
  return c;
}

// A vector as a JSON array of its 3 numbers.
nlohmann::json Vec3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

// The 3-number array at `key` of j; throws ProtocolError naming the key otherwise.
Eigen::Vector3d ReadVec3(const nlohmann::json& j, const char* key) {
  const nlohmann::json& a = j.at(key);
  if (!a.is_array() || a.size() != 3)
    throw ProtocolError(std::string(key) + ": expected 3 numbers");
  return {a[0].get<double>(), a[1].get<double>(), a[2].get<double>()};
}

// The initial state as JSON (quaternion w, x, y, z; the mode by name).
nlohmann::json StateJson(const SystemState& s) {
  return {
      {"time_s", s.time_s},       {"p_WL_W", Vec3(s.p_WL_W)},
      {"v_WL_W", Vec3(s.v_WL_W)}, {"p_WQ_W", Vec3(s.p_WQ_W)},
      {"v_WQ_W", Vec3(s.v_WQ_W)}, {"q_WB_wxyz", {s.q_WB.w(), s.q_WB.x(), s.q_WB.y(), s.q_WB.z()}},
      {"w_B", Vec3(s.w_B)},       {"mode", ToString(s.mode)}};
}

// The initial state from StateJson's JSON.
SystemState StateFromJson(const nlohmann::json& j) {
  SystemState s;
  s.time_s = j.at("time_s").get<double>();
  s.p_WL_W = ReadVec3(j, "p_WL_W"), s.v_WL_W = ReadVec3(j, "v_WL_W");
  s.p_WQ_W = ReadVec3(j, "p_WQ_W"), s.v_WQ_W = ReadVec3(j, "v_WQ_W");
  const nlohmann::json& q = j.at("q_WB_wxyz");
  s.q_WB = Eigen::Quaterniond(q.at(0).get<double>(), q.at(1).get<double>(), q.at(2).get<double>(),
                              q.at(3).get<double>());
  s.w_B = ReadVec3(j, "w_B");
  s.mode = j.at("mode").get<std::string>() == "slack" ? CableMode::kSlack : CableMode::kTaut;
  return s;
}

// Every declared field of `config` as the protocol names it (the tables' wire names): numbers
// as numbers, switches as booleans, vectors as arrays, a matrix as its numbers row by row.
template <class C>
nlohmann::json TablesToJson(const std::vector<ParamTable<C>>& tables, const C& config) {
  nlohmann::json out = nlohmann::json::object();
  for (const ParamTable<C>& table : tables) {
    for (const ParamDecl<C>& d : table.params) {
      const std::string& name = d.wire_key.empty() ? d.key : d.wire_key;
      std::visit(
          [&](auto member) {
            using T = std::decay_t<decltype(config.*member)>;
            if constexpr (std::is_same_v<T, double> || std::is_same_v<T, int> ||
                          std::is_same_v<T, bool>) {
              out[name] = config.*member;
            } else {
              nlohmann::json values = nlohmann::json::array();
              const auto& m = config.*member;
              for (Eigen::Index i = 0; i < m.rows(); ++i) {
                for (Eigen::Index j = 0; j < m.cols(); ++j) values.push_back(m(i, j));
              }
              out[name] = values;
            }
          },
          d.member);
    }
  }
  return out;
}

// Reads every declared field of `*config` from TablesToJson's JSON, each value checked against
// its declared range (per element where it has one); throws ProtocolError naming
// SECTION.field.
template <class C>
void TablesFromJson(const std::vector<ParamTable<C>>& tables, const nlohmann::json& j,
                    const std::string& section, C* config) {
  for (const ParamTable<C>& table : tables) {
    for (const ParamDecl<C>& d : table.params) {
      const std::string& name = d.wire_key.empty() ? d.key : d.wire_key;
      const auto in_range = [&](double v, size_t element) {
        const auto [min, max] = ElementRange(d, element);
        if (!(v >= min && v <= max)) {
          throw ProtocolError(section + "." + name + ": " + std::to_string(v) + " outside " +
                              std::to_string(min) + " to " + std::to_string(max));
        }
        return v;
      };
      std::visit(
          [&](auto member) {
            using T = std::decay_t<decltype(config->*member)>;
            const nlohmann::json& v = j.at(name);
            if constexpr (std::is_same_v<T, bool>) {
              config->*member = v.get<bool>();
            } else if constexpr (std::is_same_v<T, int>) {
              config->*member = static_cast<int>(in_range(v.get<int>(), 0));
            } else if constexpr (std::is_same_v<T, double>) {
              config->*member = in_range(v.get<double>(), 0);
            } else {
              auto& m = config->*member;
              if (!v.is_array() || v.size() != static_cast<size_t>(m.size())) {
                throw ProtocolError(section + "." + name + ": expected " +
                                    std::to_string(m.size()) + " numbers");
              }
              for (Eigen::Index i = 0; i < m.rows(); ++i) {
                for (Eigen::Index k = 0; k < m.cols(); ++k) {
                  const Eigen::Index at = i * m.cols() + k;
                  m(i, k) = in_range(v.at(at).template get<double>(), static_cast<size_t>(at));
                }
              }
            }
          },
          d.member);
    }
  }
}

}  // namespace

nlohmann::json ParamsToJson(const Params& params) { return TablesToJson(ParamsTables(), params); }

Params ParamsFromJson(const nlohmann::json& j, const std::string& section) {
  try {
    Params params;
    TablesFromJson(ParamsTables(), j, section, &params);
    return params;
  } catch (const nlohmann::json::exception& e) {
    throw ProtocolError("bad " + section + ": " + e.what());
  }
}

nlohmann::json ReferenceToJson(const ReferenceSpec& r) {
  const LissajousSpec& l = r.lissajous;
  nlohmann::json reference = {{"type", r.type},
                              {"payload_position_W_m", Vec3(r.payload_position_W_m)},
                              {"lissajous",
                               {{"a", l.a},
                                {"b", l.b},
                                {"c", l.c},
                                {"n", l.n},
                                {"m", l.m},
                                {"phi", l.phi},
                                {"psi", l.psi},
                                {"period_s", l.period_s},
                                {"ramp_s", l.ramp_s},
                                {"centre", Vec3(l.centre)}}},
                              {"line_start_W_m", Vec3(r.line_start_W_m)},
                              {"line_end_W_m", Vec3(r.line_end_W_m)},
                              {"line_duration_s", r.line_duration_s},
                              {"line_start_time_s", r.line_start_time_s},
                              {"file", r.file}};
  nlohmann::json samples = nlohmann::json::array();
  for (const TrajectorySample& s : r.samples) {
    samples.push_back({s.t_s, s.p_WL_W.x(), s.p_WL_W.y(), s.p_WL_W.z(), s.v_WL_W.x(), s.v_WL_W.y(),
                       s.v_WL_W.z(), s.a_WL_W.x(), s.a_WL_W.y(), s.a_WL_W.z()});
  }
  reference["samples_t_p_v_a"] = samples;
  // a type that keeps its key values as read (one registered beyond the built-ins) sends them
  if (!r.values.empty()) reference["key_values"] = r.values;
  return reference;
}

nlohmann::json ConfigToJson(const FlightConfig& c) {
  return {{"params", ParamsToJson(c.params)},
          {"controller", ControllerToJson(c.controller)},
          {"estimator", c.estimator},
          {"slack_tension_cue", c.slack_tension_cue},
          {"reference", ReferenceToJson(c.reference)},
          {"ground_truth", c.ground_truth},
          {"estimate_latency_s", c.estimate_latency_s},
          {"tick_hz", c.tick_hz},
          {"initial_state", StateJson(c.initial_state)}};
}

nlohmann::json RateLoopToJson(const RateLoopConfig& config) {
  return {{"px4", config.spec.px4},
          {"own_rate_hz", config.own_rate_hz},
          {"params", TablesToJson({Px4RateParamTable()}, config.spec.params)}};
}

RateLoopConfig RateLoopFromJson(const nlohmann::json& j) {
  try {
    RateLoopConfig c;
    c.spec.px4 = j.at("px4").get<bool>();
    c.own_rate_hz = j.at("own_rate_hz").get<double>();
    if (!(std::isfinite(c.own_rate_hz) && c.own_rate_hz > 0.0)) {
      throw ProtocolError("rate_loop.own_rate_hz: " + std::to_string(c.own_rate_hz) +
                          ", expected a rate > 0 Hz");
    }
    TablesFromJson({Px4RateParamTable()}, j.at("params"), "rate_loop.params", &c.spec.params);
    return c;
  } catch (const nlohmann::json::exception& e) {
    throw ProtocolError(std::string("bad rate_loop in the hello: ") + e.what());
  }
}

namespace {

// The reference spec of ReferenceToJson's JSON; throws nlohmann::json::exception for a missing
// key or a value of another type, ProtocolError for one outside its declaration.
ReferenceSpec ReadReference(const nlohmann::json& rj) {
  ReferenceSpec r;
  r.type = rj.at("type").get<std::string>();
  r.payload_position_W_m = ReadVec3(rj, "payload_position_W_m");
  const nlohmann::json& lj = rj.at("lissajous");
  LissajousSpec& l = r.lissajous;
  l.a = lj.at("a").get<double>(), l.b = lj.at("b").get<double>(), l.c = lj.at("c").get<double>();
  l.n = lj.at("n").get<double>(), l.m = lj.at("m").get<double>();
  l.phi = lj.at("phi").get<double>(), l.psi = lj.at("psi").get<double>();
  l.period_s = lj.at("period_s").get<double>(), l.ramp_s = lj.at("ramp_s").get<double>();
  l.centre = ReadVec3(lj, "centre");
  r.line_start_W_m = ReadVec3(rj, "line_start_W_m");
  r.line_end_W_m = ReadVec3(rj, "line_end_W_m");
  r.line_duration_s = rj.at("line_duration_s").get<double>();
  r.line_start_time_s = rj.at("line_start_time_s").get<double>();
  r.file = rj.value("file", "");
  for (const nlohmann::json& row : rj.value("samples_t_p_v_a", nlohmann::json::array())) {
    if (!row.is_array() || row.size() != 10) {
      throw ProtocolError("reference samples: expected rows of 10 numbers");
    }
    TrajectorySample s;
    s.t_s = row[0].get<double>();
    s.p_WL_W = {row[1].get<double>(), row[2].get<double>(), row[3].get<double>()};
    s.v_WL_W = {row[4].get<double>(), row[5].get<double>(), row[6].get<double>()};
    s.a_WL_W = {row[7].get<double>(), row[8].get<double>(), row[9].get<double>()};
    r.samples.push_back(s);
  }
  if (rj.contains("key_values")) {
    r.values = rj.at("key_values").get<std::map<std::string, std::vector<double>>>();
  }
  // the type is one this stack has, its key values within the ranges it declares
  if (const std::optional<std::string> error = ReferenceValuesError(r)) {
    throw ProtocolError("reference: " + *error);
  }
  return r;
}

}  // namespace

ReferenceSpec ReferenceFromJson(const nlohmann::json& j) {
  try {
    return ReadReference(j);
  } catch (const nlohmann::json::exception& e) {
    throw ProtocolError(std::string("bad reference: ") + e.what());
  }
}

FlightConfig ConfigFromJson(const nlohmann::json& j) {
  try {
    FlightConfig c;
    TablesFromJson(ParamsTables(), j.at("params"), "params", &c.params);
    c.controller = ControllerFromJson(j.at("controller"));
    c.estimator = j.at("estimator").get<std::string>();
    c.slack_tension_cue = j.at("slack_tension_cue").get<bool>();
    c.reference = ReadReference(j.at("reference"));
    c.ground_truth = j.at("ground_truth").get<bool>();
    c.estimate_latency_s = j.at("estimate_latency_s").get<double>();
    c.tick_hz = j.at("tick_hz").get<double>();
    c.initial_state = StateFromJson(j.at("initial_state"));
    return c;
  } catch (const nlohmann::json::exception& e) {
    throw ProtocolError(std::string("bad flight config in the hello: ") + e.what());
  }
}

}  // namespace hpa::flight
