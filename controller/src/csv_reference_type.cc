// The csv reference type: a payload trajectory sampled in a file (reference.h's reader).

#include "hpa/controller/reference_types.h"

namespace hpa {

/// The csv reference type's keys and behaviour (registered in reference_types.cc).
ReferenceType CsvReferenceType() {
  return {"csv",
          "samples from a file: t_s, x_m, y_m, z_m [, vx_mps, vy_mps, vz_mps] [, ax_mps2, "
          "ay_mps2, az_mps2]; linear between samples, the last held at rest",
          {{"file", "", 0, 0, 0, std::nullopt,
            "the CSV, relative to the scenario file (docs/design.md section 5)"}},
          [](const ReferenceKeyValues& v, ReferenceSpec* spec) {
            // positions within the one bound every reference position shares
            const PositionRange range{-kReferencePositionBound_m, kReferencePositionBound_m};
            spec->samples = v.file_text ? ParseTrajectoryCsv(*v.file_text, spec->file, range)
                                        : LoadTrajectoryCsv(spec->file, range);
          },
          // a CSV flies its samples from the first
          [](const ReferenceSpec&) { return 0.0; },
          [](const ReferenceSpec& spec, const Params& params) {
            // the quadrotor reference depends on params (gravity, cable length): checked here,
            // by line
            CheckSampledReference(params, spec.samples, spec.file);
            return MakeSampledReference(params, spec.samples);
          }};
}

}  // namespace hpa
