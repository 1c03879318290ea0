// The line reference type: a straight line with a minimum-jerk time law, from a start time on.

#include <memory>
#include <utility>

#include "hpa/controller/reference_types.h"

namespace hpa {
namespace {

// The line reference holds its start before t = 0; shifted so it starts at start_time.
class DelayedReference : public Reference {
 public:
  DelayedReference(std::shared_ptr<Reference> inner, double delay_s)
      : inner_(std::move(inner)), delay_s_(delay_s) {}
  ReferencePoint At(double t_s) const override { return inner_->At(t_s - delay_s_); }

 private:
  std::shared_ptr<Reference> inner_;
  double delay_s_;
};

}  // namespace

/// The line reference type's keys and behaviour (registered in reference_types.cc).
ReferenceType LineReferenceType() {
  constexpr double kBound_m = kReferencePositionBound_m;
  return {"line",
          "a straight line from start to end with a minimum-jerk time law, holding start "
          "before start_time",
          {{"start", "m", 3, -kBound_m, kBound_m, std::nullopt, "where it starts (world)"},
           {"end", "m", 3, -kBound_m, kBound_m, std::nullopt, "where it ends (world)"},
           {"duration", "s", 1, 1e-3, 1e5, std::nullopt, "time from start to end"},
           {"start_time", "s", 1, 0.0, 1e5, 0.0, "when it starts moving"}},
          [](const ReferenceKeyValues& v, ReferenceSpec* spec) {
            spec->line_start_W_m = v.Vector3("start");
            spec->line_end_W_m = v.Vector3("end");
            spec->line_duration_s = v.Number("duration");
            spec->line_start_time_s = v.Number("start_time");
          },
          // a line holds its start until it moves: its RMSE counts from the start
          [](const ReferenceSpec&) { return 0.0; },
          [](const ReferenceSpec& spec, const Params& params) -> std::shared_ptr<Reference> {
            return std::make_shared<DelayedReference>(
                MakeLineReference(params, spec.line_start_W_m, spec.line_end_W_m,
                                  spec.line_duration_s),
                spec.line_start_time_s);
          }};
}

}  // namespace hpa
