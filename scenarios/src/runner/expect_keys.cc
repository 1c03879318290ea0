#include "hpa/scenarios/expect_keys.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "hpa/models/registry.h"
#include "hpa/scenarios/metrics.h"

namespace hpa {
namespace {

constexpr double kBig = 1e3;  // generous bound on lengths (m), speeds (m/s), times (s)

std::string Failure(const std::string& key, double value, const char* op, double bound) {
  std::ostringstream out;
  out << key << ": " << value << " " << op << " " << bound;
  return out.str();
}

// metric <= bound (metric > bound fails), per value
ExpectKey Max(std::string key, std::string metric, std::string unit, std::string description,
              double max, std::function<double(const Metrics&)> read) {
  ExpectKey k{key, metric, "metric <= bound", unit, description, 1, 0.0, max, false, {}};
  k.check = [key, read](const Metrics& m, const std::vector<double>& bound) {
    const double v = read(m);
    if (std::isnan(v)) return std::vector<std::string>{key + ": not measured in this run"};
    return v > bound[0] ? std::vector<std::string>{Failure(key, v, ">", bound[0])}
                        : std::vector<std::string>{};
  };
  return k;
}

// metric >= bound (metric < bound fails)
ExpectKey Min(std::string key, std::string metric, std::string unit, std::string description,
              double min, double max, std::function<double(const Metrics&)> read) {
  ExpectKey k{key, metric, "metric >= bound", unit, description, 1, min, max, false, {}};
  k.check = [key, read](const Metrics& m, const std::vector<double>& bound) {
    const double v = read(m);
    if (std::isnan(v)) return std::vector<std::string>{key + ": not measured in this run"};
    return v < bound[0] ? std::vector<std::string>{Failure(key, v, "<", bound[0])}
                        : std::vector<std::string>{};
  };
  return k;
}

// per-axis metric <= bound, each axis named
ExpectKey AxesMax(std::string key, std::string metric, std::string description,
                  std::function<Eigen::Vector3d(const Metrics&)> read) {
  ExpectKey k{key, metric, "metric <= bound, per axis", "m", description, 3, 0.0, kBig, false, {}};
  k.check = [key, read](const Metrics& m, const std::vector<double>& bound) {
    static const char* kAxes[3] = {"x", "y", "z"};
    std::vector<std::string> failed;
    const Eigen::Vector3d v = read(m);
    for (int i = 0; i < 3; ++i) {
      if (v(i) > bound[i]) failed.push_back(Failure(key + "." + kAxes[i], v(i), ">", bound[i]));
    }
    return failed;
  };
  return k;
}

std::vector<ExpectKey> BuildTable() {
  std::vector<ExpectKey> t;
  {
    ExpectKey k{"crashed",
                "crashed",
                "metric == bound",
                "true | false",
                "whether the run must crash (false: any crash fails)",
                0,
                0.0,
                1.0,
                false,
                {}};
    k.check = [](const Metrics& m, const std::vector<double>& bound) {
      const bool expected = bound[0] != 0.0;
      if (expected == m.crashed) return std::vector<std::string>{};
      return std::vector<std::string>{std::string("crashed: ") + (m.crashed ? "true" : "false") +
                                      (m.crashed ? " (" + m.crash_reason.value_or("") + ")" : "") +
                                      ", expected " + (expected ? "true" : "false")};
    };
    t.push_back(k);
  }
  {
    // read by CheckExpectations: a crash fails every scenario that neither bounds `crashed` nor
    // allows one
    ExpectKey k{"crash_allowed",
                "crashed",
                "always (a crash is then no failure)",
                "true | false",
                "true: a crash is no failure of this scenario (a diagnostic case whose other "
                "bounds are its verdict)",
                0,
                0.0,
                1.0,
                false,
                {}};
    k.check = [](const Metrics&, const std::vector<double>&) { return std::vector<std::string>{}; };
    t.push_back(k);
  }
  t.push_back(AxesMax("payload_rmse_max", "payload_rmse_m", "payload tracking RMSE per axis",
                      [](const Metrics& m) { return m.payload_rmse_m; }));
  t.push_back(AxesMax("quad_rmse_max", "quad_rmse_m", "quadrotor tracking RMSE per axis",
                      [](const Metrics& m) { return m.quad_rmse_m; }));
  t.push_back(Max("quad_position_deviation_max", "quad_position_deviation_max_m", "m",
                  "largest quadrotor distance from its reference", kBig,
                  [](const Metrics& m) { return m.quad_position_deviation_max_m; }));
  t.push_back(Min("quad_position_deviation_min", "quad_position_deviation_max_m", "m",
                  "a baseline must show its failure: at least this far off", 0.0, kBig,
                  [](const Metrics& m) { return m.quad_position_deviation_max_m; }));
  t.push_back(Max("payload_in_fov_max", "payload_in_fov_fraction", "fraction",
                  "share of camera frames with the payload in view, at most", 1.0,
                  [](const Metrics& m) { return m.payload_in_fov_fraction; }));
  t.push_back(Min("payload_in_fov_min", "payload_in_fov_fraction", "fraction",
                  "share of camera frames with the payload in view, at least", 0.0, 1.0,
                  [](const Metrics& m) { return m.payload_in_fov_fraction; }));
  t.push_back(Min("mode_accuracy_min", "mode_accuracy", "fraction",
                  "share of control steps whose estimated mode is the true one", 0.0, 1.0,
                  [](const Metrics& m) { return m.mode_accuracy; }));
  {
    ExpectKey k{"slack_detection_latency_max",
                "slack_detection_latency_s.max",
                "metric <= bound",
                "s",
                "slowest slack detection; a missed slack event fails",
                1,
                0.0,
                kBig,
                false,
                {}};
    k.check = [](const Metrics& m, const std::vector<double>& bound) {
      if (m.slack_events_missed > 0) {
        return std::vector<std::string>{Failure("slack_detection_latency_max (missed slack events)",
                                                m.slack_events_missed, ">", 0)};
      }
      if (m.slack_detection_latency_max_s && *m.slack_detection_latency_max_s > bound[0]) {
        return std::vector<std::string>{Failure("slack_detection_latency_max",
                                                *m.slack_detection_latency_max_s, ">", bound[0])};
      }
      return std::vector<std::string>{};
    };
    t.push_back(k);
  }
  {
    ExpectKey k = Max("mpc_failures_max", "mpc_failures", "updates",
                      "MPC updates with a QP failure, non-finite result or fallback", 1e9,
                      [](const Metrics& m) { return static_cast<double>(m.mpc_failures); });
    k.integer = true;
    t.push_back(k);
  }
  t.push_back(Min("retaut_quad_vz_min", "retaut.quad_vz_min_mps", "m/s",
                  "lowest quadrotor z velocity within 0.5 s of a re-taut, at least", -kBig, kBig,
                  [](const Metrics& m) { return m.retaut_quad_vz_min_mps.value_or(NAN); }));
  t.push_back(Max("retaut_peak_body_rate_max", "retaut.peak_body_rate_radps", "rad/s",
                  "highest body rate within 0.5 s of a re-taut, at most", kBig,
                  [](const Metrics& m) { return m.retaut_peak_body_rate_radps.value_or(NAN); }));
  t.push_back(Min("payload_quad_min_distance_min", "payload_quad_min_distance_m", "m",
                  "smallest payload-to-vehicle surface distance, at least (< 0: overlap)", -kBig,
                  kBig, [](const Metrics& m) { return m.payload_quad_min_distance_m; }));
  return t;
}

Registry<ExpectKey>& TheRegistry() {
  static Registry<ExpectKey> registry("expect key", BuildTable());
  return registry;
}

}  // namespace

const std::vector<ExpectKey>& ExpectKeys() { return TheRegistry().All(); }

const ExpectKey* FindExpectKey(const std::string& key) { return TheRegistry().Find(key); }

void RegisterExpectKey(ExpectKey key) {
  if (!key.check)
    throw std::invalid_argument("register expect key: '" + key.key + "' has no check");
  TheRegistry().Add(std::move(key));
}

}  // namespace hpa
