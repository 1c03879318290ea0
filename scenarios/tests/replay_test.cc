// hpa replay renders from the logged states: the payload the detector finds in each replayed
// onboard frame is where the logged true state puts it, and a broken log is refused by line.
#include "hpa/scenarios/replay.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "hpa/estimator/payload_detector.h"
#include "hpa/models/camera_model.h"
#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/models/yaml_reader.h"
#include "hpa/scenarios/run_record.h"
#include "hpa/scenarios/runner.h"
#include "models/tests/temp_dir.h"

namespace hpa {
namespace {

const std::string kScenario = std::string(HPA_SOURCE_DIR) + "/scenarios/line_impulse.yaml";

// A 5.5 s line_impulse run (the push at 5 s swings the payload) written as hpa run writes it.
std::string RecordedRun() {
  const std::string dir = TestTempDir();
  RunRecord record;
  record.scenario_file = kScenario;
  record.scenario_text = ReadYamlFile(kScenario);
  record.sets = {{"duration", "5.5"}, {"estimation.camera", "analytic"}};
  record.params = LoadParams(DefaultParamsPath());
  WriteRunRecord(dir, record);
  const RunResult result = RunScenario(ScenarioOf(record), record.params, RunOptions{});
  EXPECT_FALSE(result.metrics.crashed);
  WriteLogCsv(dir + "/log.csv", result.rows);
  return dir;
}

TEST(ReplayTest, FramesShowTheLoggedStates) {
  const std::string dir = RecordedRun();
  const Params params = LoadParams(DefaultParamsPath());
  PayloadDetector detector(params);
  ReplayOptions options;
  options.dir = dir;
  double worst_m = 0.0, worst_row_gap_s = 0.0;
  int detected = 0;
  const int frames = ReplayRun(options, [&](const ReplayFrame& f) {
    worst_row_gap_s = std::max(worst_row_gap_s, std::abs(f.time_s - f.row->time_s));
    const PayloadDetection d = detector.Detect(f.onboard, f.time_s);
    if (!d.found) return;
    ++detected;
    const Eigen::Vector3d logged_C = PayloadInCamera_C(params, f.row->truth);
    worst_m = std::max(worst_m, (d.p_CL_C - logged_C).norm());
  });
  std::printf(
      "[measured] %d frames, %d detected, worst detection vs logged state %.4f m, "
      "row gap %.4f s\n",
      frames, detected, worst_m, worst_row_gap_s);
  EXPECT_EQ(frames, 166);  // 5.5 s at 30 Hz, t = 0 included
  EXPECT_GE(detected, frames - 2);
  // each frame shows the row logged at its tick (control steps land on the video ticks; the
  // log's times have seven digits)
  EXPECT_LT(worst_row_gap_s, 1e-5);
  // the detector on the flight profile's rendered frames errs by millimetres at 0.5 m (measured
  // worst over this run 0.0084 m, the payload swinging after the push); a frame rendered one
  // control step (6.7 ms) off the logged state while it swings at up to 1 m/s adds up to
  // 7 mm: bound 0.012 m (the measurement plus 40 %)
  EXPECT_LT(worst_m, 0.012);
}

TEST(ReplayTest, ABrokenLogIsRefusedByLine) {
  const std::string dir = TestTempDir();
  std::ofstream(dir + "/log.csv") << "time_s,true_pL_x\n0,1\n";
  try {
    ReadLogCsv(dir + "/log.csv");
    FAIL() << "a log without its columns was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no column"), std::string::npos) << e.what();
  }
  const std::string run = RecordedRun();
  std::ifstream in(run + "/log.csv");
  std::string header, row;
  std::getline(in, header);
  std::getline(in, row);
  std::ofstream(dir + "/cut.csv") << header << "\n" << row << "\n" << row.substr(0, 40) << "\n";
  try {
    ReadLogCsv(dir + "/cut.csv");
    FAIL() << "a truncated log was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
  try {
    ReadRunRecord(dir + "/nothing");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("run.json"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hpa
