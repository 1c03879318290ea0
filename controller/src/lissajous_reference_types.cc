// The Lissajous family of reference types: the paper's Lissajous and its circle and figure-eight
// spellings. All three fly MakeLissajousReference, share the keys period, ramp and centre, and
// start their RMSE at the end of the ramp.

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "hpa/controller/reference_types.h"

namespace hpa {
namespace {

// Keys the Lissajous family shares.
std::vector<ReferenceKey> PeriodRampCentre() {
  return {{"period", "s", 1, 0.1, 1e4, 5.0, "period T of one cycle (w = 2 pi / T)"},
          {"ramp", "s", 1, 0.0, 1e4, 2.0,
           "the phase rate ramps smoothly (C2) from 0 to w over this time: the payload starts "
           "at rest"},
          {"centre", "m", 3, -kReferencePositionBound_m, kReferencePositionBound_m, 0.0,
           "added to the whole path (world)"}};
}

// A family member: `keys` followed by the shared ones, `read` filling the spec's Lissajous
// before the shared keys are read into it.
ReferenceType FamilyMember(std::string name, std::string description,
                           std::vector<ReferenceKey> keys, ReferenceReader read) {
  for (const ReferenceKey& k : PeriodRampCentre()) keys.push_back(k);
  return {std::move(name), std::move(description), std::move(keys),
          [read](const ReferenceKeyValues& v, ReferenceSpec* spec) {
            read(v, spec);
            LissajousSpec& s = spec->lissajous;
            s.period_s = v.Number("period");
            s.ramp_s = v.Number("ramp");
            s.centre = v.Vector3("centre");
          },
          // the phase rate ramps up over the first `ramp` seconds: the RMSE starts at its end
          [](const ReferenceSpec& spec) { return spec.lissajous.ramp_s; },
          [](const ReferenceSpec& spec, const Params& params) {
            return MakeLissajousReference(params, spec.lissajous);
          }};
}

}  // namespace

/// The Lissajous reference type's keys and behaviour (registered in reference_types.cc).
ReferenceType LissajousReferenceType() {
  return FamilyMember(
      "lissajous",
      "the paper's Lissajous: x_L = [a sin(theta), b sin(n theta + phi), c sin(m theta) + psi] + "
      "centre, theta = w t (its rate ramped over `ramp`)",
      {{"a", "m", 1, -100, 100, 2.0, "x amplitude"},
       {"b", "m", 1, -100, 100, 0.5, "y amplitude"},
       {"c", "m", 1, -100, 100, 0.0, "z amplitude"},
       {"n", "-", 1, -100, 100, 2.0, "y frequency multiple"},
       {"m", "-", 1, -100, 100, 1.0, "z frequency multiple"},
       {"phi", "rad", 1, -100, 100, 0.0, "y phase"},
       {"psi", "m", 1, -100, 100, 1.0, "height offset"}},
      [](const ReferenceKeyValues& v, ReferenceSpec* spec) {
        LissajousSpec& s = spec->lissajous;
        s.a = v.Number("a");
        s.b = v.Number("b");
        s.c = v.Number("c");
        s.n = v.Number("n");
        s.m = v.Number("m");
        s.phi = v.Number("phi");
        s.psi = v.Number("psi");
      });
}

/// The circle reference type's keys and behaviour (registered in reference_types.cc).
ReferenceType CircleReferenceType() {
  return FamilyMember("circle",
                      "the Lissajous with a = b = radius, n = 1, phi = pi/2, c = 0: "
                      "x = r sin(theta), y = r cos(theta), at `height`",
                      {{"radius", "m", 1, 0.01, 100, std::nullopt, "circle radius"},
                       {"height", "m", 1, 0.1, 100, 1.0, "payload height (psi)"}},
                      [](const ReferenceKeyValues& v, ReferenceSpec* spec) {
                        LissajousSpec& s = spec->lissajous;
                        s.a = s.b = v.Number("radius");
                        s.n = 1.0;
                        s.phi = M_PI / 2.0;
                        s.c = 0.0;
                        s.psi = v.Number("height");
                      });
}

/// The figure-eight reference type's keys and behaviour (registered in reference_types.cc).
ReferenceType FigureEightReferenceType() {
  return FamilyMember(
      "figure_eight",
      "the Lissajous with a = half_length, b = half_width, n = 2, phi = 0, c = 0: "
      "x = a sin(theta), y = b sin(2 theta), at `height`",
      {{"half_length", "m", 1, 0.01, 100, std::nullopt, "half the eight's length (x)"},
       {"half_width", "m", 1, 0.01, 100, std::nullopt, "half the eight's width (y)"},
       {"height", "m", 1, 0.1, 100, 1.0, "payload height (psi)"}},
      [](const ReferenceKeyValues& v, ReferenceSpec* spec) {
        LissajousSpec& s = spec->lissajous;
        s.a = v.Number("half_length");
        s.b = v.Number("half_width");
        s.n = 2.0;
        s.phi = 0.0;
        s.c = 0.0;
        s.psi = v.Number("height");
      });
}

}  // namespace hpa
