#include "hpa/controller/reference_spec.h"

#include <utility>

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

namespace {

// The Lissajous family: the Lissajous itself and its circle and figure-eight spellings.
bool IsLissajousFamily(const ReferenceSpec& r) {
  return r.type == "lissajous" || r.type == "circle" || r.type == "figure_eight";
}

}  // namespace

double RmseFromS(const ReferenceSpec& r) {
  // a Lissajous ramps its rate up over its first `ramp` seconds; the others start as they fly
  return IsLissajousFamily(r) ? r.lissajous.ramp_s : 0.0;
}

std::shared_ptr<Reference> MakeReference(const ReferenceSpec& r, const Params& params) {
  if (IsLissajousFamily(r)) {
    return MakeLissajousReference(params, r.lissajous);
  }
  if (r.type == "csv") {
    // the quadrotor reference depends on params (gravity, cable length): checked here, by line
    CheckSampledReference(params, r.samples, r.file);
    return MakeSampledReference(params, r.samples);
  }
  if (r.type == "line") {
    return std::make_shared<DelayedReference>(
        MakeLineReference(params, r.line_start_W_m, r.line_end_W_m, r.line_duration_s),
        r.line_start_time_s);
  }
  return MakeHoverReference(params, r.payload_position_W_m);
}

}  // namespace hpa
