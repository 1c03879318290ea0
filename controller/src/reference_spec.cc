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

std::shared_ptr<Reference> MakeReference(const ReferenceSpec& r, const Params& params) {
  if (r.type == "lissajous" || r.type == "circle" || r.type == "figure_eight") {
    return MakeLissajousReference(params, r.lissajous);
  }
  if (r.type == "csv") return MakeSampledReference(params, r.samples);
  if (r.type == "line") {
    return std::make_shared<DelayedReference>(
        MakeLineReference(params, r.line_start_W_m, r.line_end_W_m, r.line_duration_s),
        r.line_start_time_s);
  }
  return MakeHoverReference(params, r.payload_position_W_m);
}

}  // namespace hpa
