#include "hpa/scenarios/reference_types.h"

#include <stdexcept>

namespace hpa {
namespace {

constexpr double kBig = 1e3;  // m: far beyond the 20 m arena, only a guard against typos

// Keys the Lissajous family shares.
std::vector<ReferenceKey> PeriodRampCentre() {
  return {{"period", "s", 1, 0.1, 1e4, 5.0, "period T of one cycle (w = 2 pi / T)"},
          {"ramp", "s", 1, 0.0, 1e4, 2.0,
           "the phase rate ramps smoothly (C2) from 0 to w over this time: the payload starts "
           "at rest"},
          {"centre", "m", 3, -kBig, kBig, 0.0, "added to the whole path (world)"}};
}

std::vector<ReferenceType> Build() {
  std::vector<ReferenceType> t;
  t.push_back({"hover",
               "a constant payload position",
               {{"payload_position", "m", 3, -kBig, kBig, std::nullopt,
                 "the payload's set-point (world)"}}});
  ReferenceType lissajous{
      "lissajous",
      "the paper's Lissajous: x_L = [a sin(theta), b sin(n theta + phi), c sin(m theta) + psi] + "
      "centre, theta = w t (its rate ramped over `ramp`)",
      {{"a", "m", 1, -100, 100, 2.0, "x amplitude"},
       {"b", "m", 1, -100, 100, 0.5, "y amplitude"},
       {"c", "m", 1, -100, 100, 0.0, "z amplitude"},
       {"n", "-", 1, -100, 100, 2.0, "y frequency multiple"},
       {"m", "-", 1, -100, 100, 1.0, "z frequency multiple"},
       {"phi", "rad", 1, -100, 100, 0.0, "y phase"},
       {"psi", "m", 1, -100, 100, 1.0, "height offset"}}};
  for (const ReferenceKey& k : PeriodRampCentre()) lissajous.keys.push_back(k);
  t.push_back(lissajous);
  t.push_back({"line",
               "a straight line from start to end with a minimum-jerk time law, holding start "
               "before start_time",
               {{"start", "m", 3, -kBig, kBig, std::nullopt, "where it starts (world)"},
                {"end", "m", 3, -kBig, kBig, std::nullopt, "where it ends (world)"},
                {"duration", "s", 1, 1e-3, 1e5, std::nullopt, "time from start to end"},
                {"start_time", "s", 1, 0.0, 1e5, 0.0, "when it starts moving"}}});
  ReferenceType circle{
      "circle",
      "the Lissajous with a = b = radius, n = 1, phi = pi/2, c = 0: x = r sin(theta), "
      "y = r cos(theta), at `height`",
      {{"radius", "m", 1, 0.01, 100, std::nullopt, "circle radius"},
       {"height", "m", 1, 0.1, 100, 1.0, "payload height (psi)"}}};
  for (const ReferenceKey& k : PeriodRampCentre()) circle.keys.push_back(k);
  t.push_back(circle);
  ReferenceType eight{
      "figure_eight",
      "the Lissajous with a = half_length, b = half_width, n = 2, phi = 0, c = 0: "
      "x = a sin(theta), y = b sin(2 theta), at `height`",
      {{"half_length", "m", 1, 0.01, 100, std::nullopt, "half the eight's length (x)"},
       {"half_width", "m", 1, 0.01, 100, std::nullopt, "half the eight's width (y)"},
       {"height", "m", 1, 0.1, 100, 1.0, "payload height (psi)"}}};
  for (const ReferenceKey& k : PeriodRampCentre()) eight.keys.push_back(k);
  t.push_back(eight);
  t.push_back({"csv",
               "samples from a file: t_s, x_m, y_m, z_m [, vx_mps, vy_mps, vz_mps] [, ax_mps2, "
               "ay_mps2, az_mps2]; linear between samples, the last held at rest",
               {{"file", "", 0, 0, 0, std::nullopt,
                 "the CSV, relative to the scenario file (docs/design.md section 5)"}}});
  return t;
}

}  // namespace

const std::vector<ReferenceType>& ReferenceTypes() {
  static const std::vector<ReferenceType> types = Build();
  return types;
}

const ReferenceKey& FindReferenceKey(const std::string& type, const std::string& key) {
  for (const ReferenceType& t : ReferenceTypes()) {
    if (t.name != type) continue;
    for (const ReferenceKey& k : t.keys) {
      if (k.key == key) return k;
    }
  }
  throw std::out_of_range("no reference key " + type + "." + key);
}

}  // namespace hpa
