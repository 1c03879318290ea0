// A run's setup from its scenario, before the first tick: the starting state, the check that
// the vehicle can fly the scenario, and the world's and the flight stack's configurations.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "hpa/models/input_error.h"
#include "harness/runner/src/run_loop.h"

namespace hpa::runner {

SystemState InitialState(const Reference& reference, const Params& params) {
  SystemState s;
  const ReferencePoint r = reference.At(0.0);
  s.p_WL_W = r.p_WL_W;
  s.p_WQ_W = r.p_WL_W + Eigen::Vector3d(0, 0, params.cable_length_m);
  s.mode = CableMode::kTaut;
  return s;
}

namespace {

// "0.7" with up to 4 significant digits, for messages.
std::string Num(double v) {
  std::ostringstream out;
  out.precision(4);
  out << v;
  return out.str();
}

}  // namespace

void CheckFlyable(const Reference& reference, const Scenario& scenario, const Params& params) {
  const double duration_s = scenario.duration_s;
  const std::string& file = scenario.file;
  // hover within the motors' range: full thrust at least 1.25 x the weight (hover at most 80 %
  // of it, leaving a fifth to steer with: a quadrotor at its thrust limit cannot also tilt),
  // and the idle thrust below the weight (else it cannot descend)
  const double weight_N = (params.quad_mass_kg + params.payload_mass_kg) * params.gravity_mps2;
  const double thrust_max_N = 4.0 * params.RotorThrustMaxN();
  const double thrust_idle_N = 4.0 * params.RotorThrustMinN();
  constexpr double kHoverFractionMax = 0.8;
  if (!(weight_N <= kHoverFractionMax * thrust_max_N)) {
    throw InputError(file, "params",
                     "cannot hover: quadrotor and payload weigh " + Num(weight_N) +
                         " N and the four rotors give at most " + Num(thrust_max_N) +
                         " N (4 k_f w_max^2); hover must take at most 80 % of full thrust "
                         "(raise rotor.k_f_N_per_radps2 or rotor.motor_speed_max_radps, or lower "
                         "the masses or gravity_mps2)");
  }
  if (!(thrust_idle_N < kHoverFractionMax * weight_N)) {
    throw InputError(file, "params.rotor.motor_speed_min_radps",
                     "the idle thrust " + Num(thrust_idle_N) + " N is not below 80 % of the " +
                         Num(weight_N) + " N weight: the vehicle could not descend");
  }
  // geometry: the payload hangs clear of the body, and the vehicle fits in the arena
  const Eigen::Vector3d& half_B_m = params.body_half_size_m;
  if (!(params.cable_length_m > params.payload_radius_m + half_B_m.z())) {
    throw InputError(file, "params.cable.length_m",
                     "a cable of " + Num(params.cable_length_m) + " m hangs a payload of radius " +
                         Num(params.payload_radius_m) + " m into the body (half height " +
                         Num(half_B_m.z()) + " m)");
  }
  if (!(std::max(half_B_m.x(), half_B_m.y()) < 0.5 * sim::kArenaHalfWidth_m)) {
    throw InputError(file, "params.quadrotor.body_half_size_m",
                     "a body " + Num(2 * half_B_m.x()) + " x " + Num(2 * half_B_m.y()) +
                         " m wide does not fly in a " + Num(2 * sim::kArenaHalfWidth_m) +
                         " m arena");
  }
  // the reference over the whole run: the payload above the ground, the vehicle hanging above
  // it inside the arena (body included)
  for (double t_s = 0.0; t_s <= duration_s + 1e-9; t_s += 0.01) {
    const ReferencePoint r = reference.At(t_s);
    const Eigen::Vector3d p_WL_W = r.p_WL_W;
    const Eigen::Vector3d p_WQ_W = p_WL_W + Eigen::Vector3d(0, 0, params.cable_length_m);
    const std::string at = " at t = " + Num(t_s) + " s";
    if (!p_WL_W.allFinite()) throw InputError(file, "reference", "not finite" + at);
    if (!(p_WL_W.z() >= params.payload_radius_m)) {
      throw InputError(file, "reference",
                       "the payload reference is " + Num(p_WL_W.z()) + " m high" + at +
                           ": below the ground (the payload's radius, " +
                           Num(params.payload_radius_m) + " m, is the lowest it can be)");
    }
    const bool inside = std::abs(p_WQ_W.x()) + half_B_m.x() <= sim::kArenaHalfWidth_m &&
                        std::abs(p_WQ_W.y()) + half_B_m.y() <= sim::kArenaHalfWidth_m &&
                        p_WQ_W.z() + half_B_m.z() <= sim::kArenaHeight_m;
    if (!inside) {
      throw InputError(
          file, "reference",
          "puts the payload at (" + Num(p_WL_W.x()) + ", " + Num(p_WL_W.y()) + ", " +
              Num(p_WL_W.z()) + ") m" + at + ": the vehicle, " + Num(params.cable_length_m) +
              " m above it, would be outside the " + Num(2 * sim::kArenaHalfWidth_m) + " x " +
              Num(2 * sim::kArenaHalfWidth_m) + " x " + Num(sim::kArenaHeight_m) + " m arena");
    }
  }
}

}  // namespace hpa::runner

namespace hpa {

sim::WorldConfig WorldConfigOf(const Scenario& scenario, const Params& params,
                               sim::GlBackend gl_backend) {
  sim::WorldConfig world_config;
  world_config.params = params;
  world_config.overrides.payload_mass_kg = scenario.world_payload_mass_kg;
  world_config.overrides.cable_length_m = scenario.world_cable_length_m;
  world_config.seed = scenario.seed;
  world_config.rates = ScenarioRates(scenario);
  world_config.profile = scenario.world;
  world_config.gl_backend = gl_backend;
  world_config.randomize_appearance = scenario.estimation.camera_randomize;
  world_config.camera.kind = scenario.estimation.ground_truth         ? sim::CameraKind::kNone
                             : scenario.estimation.camera == "render" ? sim::CameraKind::kRendered
                                                                      : sim::CameraKind::kAnalytic;
  world_config.camera.detector_noise_scale = scenario.estimation.detector_noise_scale;
  return world_config;
}

}  // namespace hpa

namespace hpa::runner {

flight::FlightConfig FlightConfigOf(const Scenario& scenario, const Params& params,
                                    const SystemState& initial) {
  flight::FlightConfig c;
  c.params = params;
  c.controller = scenario.controller;
  c.estimator = EstimatorOf(scenario);
  c.slack_tension_cue = scenario.estimation.slack_tension_cue;
  c.reference = scenario.reference;
  c.ground_truth = scenario.estimation.ground_truth;
  c.estimate_latency_s = scenario.world.latency.estimate_s;
  c.tick_hz = 1.0 / sim::World::kPhysicsDt_s;
  c.initial_state = initial;
  return c;
}

}  // namespace hpa::runner
