#pragma once
// A payload reference as data: what a scenario's `reference:` block says, enough to build the
// same Reference in the simulator (for metrics) and in the flight stack (for its controller),
// in process or in another process (the lockstep protocol carries it in its hello).

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "hpa/controller/reference.h"
#include "hpa/models/params.h"

namespace hpa {

/// Where the payload reference comes from.
struct ReferenceSpec {
  std::string type = "hover";  // hover | lissajous | line | circle | figure_eight | csv
  Eigen::Vector3d payload_position_W_m{0, 0, 0.7};  // hover set-point  (3)
  LissajousSpec lissajous;
  Eigen::Vector3d line_start_W_m = Eigen::Vector3d::Zero();  // (3)
  Eigen::Vector3d line_end_W_m = Eigen::Vector3d::Zero();    // (3)
  double line_duration_s = 1.0;
  double line_start_time_s = 0.0;         // the line starts moving at this time
  std::string file;                       // csv: the file the samples were read from
  std::vector<TrajectorySample> samples;  // csv: the trajectory (LoadTrajectoryCsv)
};

/// Where the payload RMSE starts (s): the end of a Lissajous-family ramp, 0 for hover, line and
/// csv references (a line holds its start, a CSV flies its samples from the first).
double RmseFromS(const ReferenceSpec& spec);

/// Builds the reference a spec describes (the line delayed to its start time).
std::shared_ptr<Reference> MakeReference(const ReferenceSpec& spec, const Params& params);

}  // namespace hpa
