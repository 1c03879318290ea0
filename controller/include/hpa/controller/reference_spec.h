#pragma once
// A payload reference as data: what a scenario's `reference:` block says, enough to build the
// same Reference in the simulator (for metrics) and in the flight stack (for its controller),
// in process or in another process (the lockstep protocol carries it in its hello). What each
// type reads and builds is the type's own (reference_types.h).

#include <Eigen/Core>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "hpa/controller/reference.h"
#include "hpa/models/params.h"

namespace hpa {

/// Where the payload reference comes from: its type and the fields the built-in types fill.
struct ReferenceSpec {
  std::string type = "hover";  // a registered reference type (ReferenceTypes())
  Eigen::Vector3d payload_position_W_m{0, 0, 0.7};  // hover set-point  (3)
  LissajousSpec lissajous;                          // lissajous, circle, figure_eight
  Eigen::Vector3d line_start_W_m = Eigen::Vector3d::Zero();  // (3)
  Eigen::Vector3d line_end_W_m = Eigen::Vector3d::Zero();    // (3)
  double line_duration_s = 1.0;
  double line_start_time_s = 0.0;         // the line starts moving at this time
  std::string file;                       // the type's file key's path ("" without one)
  std::vector<TrajectorySample> samples;  // csv: the trajectory (LoadTrajectoryCsv)
  // a type without a read of its own (one registered beyond the built-ins): its number and
  // vector keys' values as read, by key (1 or 3 numbers each); empty for the built-ins
  std::map<std::string, std::vector<double>> values;
};

/// Where the payload RMSE starts (s), as the spec's type says: the end of a Lissajous-family
/// ramp, 0 for hover, line and csv references (a line holds its start, a CSV flies its samples
/// from the first). Throws std::invalid_argument for an unregistered type.
double RmseFromS(const ReferenceSpec& spec);

/// Builds the reference a spec describes with its type's factory; throws std::invalid_argument
/// for an unregistered type.
std::shared_ptr<Reference> MakeReference(const ReferenceSpec& spec, const Params& params);

}  // namespace hpa
