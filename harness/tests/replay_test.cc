// hpa replay renders from the logged states: the payload the detector finds in each replayed
// onboard frame is where the logged true state puts it. Bad input is refused by file, line and
// key before anything is rendered (a broken or edited log, run.json values, a FIFO, a rate), a
// csv reference travels inside run.json, and a stopped replay keeps the previous video.
#include "hpa/scenarios/replay.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "hpa/estimator/payload_detector.h"
#include "hpa/models/camera_model.h"
#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/models/yaml_reader.h"
#include "hpa/scenarios/run_record.h"
#include "hpa/scenarios/runner.h"
#include "models/tests/temp_dir.h"

namespace hpa {
namespace {

const std::string kScenarios = std::string(HPA_SOURCE_DIR) + "/scenarios/";

// A run of `scenario` with `sets` written into `dir` as hpa run writes it (run.json, log.csv).
void Record(const std::string& dir, const std::string& scenario,
            const std::vector<ScenarioSet>& sets) {
  RunRecord record;
  record.scenario_file = scenario;
  record.scenario_text = ReadYamlFile(scenario);
  record.sets = sets;
  record.params = LoadParams(DefaultParamsPath());
  WriteRunRecord(dir, record);
  const RunResult result = RunScenario(ScenarioOf(record), record.params, RunOptions{});
  EXPECT_FALSE(result.metrics.crashed);
  WriteLogCsv(dir + "/log.csv", result.rows);
}

// A 5.5 s line_impulse run (the push at 5 s swings the payload).
std::string RecordedRun() {
  const std::string dir = TestTempDir();
  Record(dir, kScenarios + "line_impulse.yaml",
         {{"duration", "5.5"}, {"estimation.camera", "analytic"}});
  return dir;
}

// A short hover run (geometric controller on the true state: quick) of `duration` seconds in a
// folder of its own under the test's temporary folder.
std::string HoverRun(const std::string& name, double duration_s) {
  const std::string dir = TestTempDir() + name;
  mkdir(dir.c_str(), 0755);
  Record(dir, kScenarios + "hover.yaml",
         {{"duration", std::to_string(duration_s)}, {"events.0.at", "0.5"}});
  return dir;
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Expects `f` to throw an InputError whose message holds every one of `fragments`.
template <typename F>
void ExpectInputError(F f, const std::vector<std::string>& fragments) {
  try {
    f();
    ADD_FAILURE() << "accepted; expected an error with '" << fragments.front() << "'";
  } catch (const InputError& e) {
    for (const std::string& fragment : fragments) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos)
          << "'" << fragment << "' not in: " << e.what();
    }
  }
}

TEST(ReplayTest, FramesShowTheLoggedStates) {
  const std::string dir = RecordedRun();
  const Params params = LoadParams(DefaultParamsPath());
  PayloadDetector detector(params);
  ReplayOptions options;
  options.dir = dir;
  double worst_m = 0.0, worst_row_gap_s = 0.0;
  int detected = 0;
  const ReplaySummary replay = ReplayRun(options, [&](const ReplayFrame& f) {
    worst_row_gap_s = std::max(worst_row_gap_s, std::abs(f.time_s - f.row->time_s));
    const PayloadDetection d = detector.Detect(f.onboard, f.time_s);
    if (!d.found) return;
    ++detected;
    const Eigen::Vector3d logged_C = PayloadInCamera_C(params, f.row->truth);
    worst_m = std::max(worst_m, (d.p_CL_C - logged_C).norm());
  });
  const int frames = replay.frames;
  std::printf(
      "[measured] %d frames, %d detected, worst detection vs logged state %.4f m, "
      "row gap %.4f s\n",
      frames, detected, worst_m, worst_row_gap_s);
  EXPECT_EQ(replay.stop_signal, 0);
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
  ExpectInputError([&] { ReadLogCsv(dir + "/log.csv", 10.0); }, {"no column"});
  const std::string run = HoverRun("run", 1.0);
  std::ifstream in(run + "/log.csv");
  std::string header, row;
  std::getline(in, header);
  std::getline(in, row);
  std::ofstream(dir + "/cut.csv") << header << "\n" << row << "\n" << row.substr(0, 40) << "\n";
  ExpectInputError([&] { ReadLogCsv(dir + "/cut.csv", 10.0); }, {"line 3", "truncated"});
  ExpectInputError([&] { ReadRunRecord(dir + "/nothing"); }, {"run.json"});
}

// A log whose times a run of its duration could not have written (edited to 1e9 s, 1e300 s, all
// negative, not increasing, not finite) is refused naming log.csv and the line, before a frame
// is rendered: the frame count is bounded by the run's duration (replaying the 1e9 s log took
// 3e10 frames, the 1e300 s one wrote a 0-frame video).
TEST(ReplayTest, LogTimesAreThoseOfTheRun) {
  const std::string run = HoverRun("run", 1.0);
  const std::string original = ReadText(run + "/log.csv");
  // the log's lines: header, then one row per control step
  std::vector<std::string> lines;
  std::istringstream split(original);
  for (std::string line; std::getline(split, line);) lines.push_back(line);
  ASSERT_GE(lines.size(), 4u);
  const int last = static_cast<int>(lines.size());  // the last row's line number
  // writes the log with the time of line `line_no` (1-based) replaced
  const auto with_time = [&](int line_no, const std::string& time) {
    std::string text;
    for (int i = 0; i < static_cast<int>(lines.size()); ++i) {
      const std::string& l = lines[i];
      text += (i + 1 == line_no ? time + l.substr(l.find(',')) : l) + "\n";
    }
    WriteFileAtomic(run + "/log.csv", text);
  };
  const std::vector<std::pair<std::string, int>> edits = {
      {"1e9", last}, {"1e300", last}, {"-0.5", 2}, {"0", 3}, {"inf", last}, {"nan", 2}};
  for (const auto& [time, line_no] : edits) {
    SCOPED_TRACE("time " + time + " on line " + std::to_string(line_no));
    with_time(line_no, time);
    int frames = 0;
    ReplayOptions options;
    options.dir = run;
    ExpectInputError([&] { ReplayRun(options, [&](const ReplayFrame&) { ++frames; }); },
                     {"log.csv", "line " + std::to_string(line_no)});
    EXPECT_EQ(frames, 0);
  }
  // every time negative: refused at the first row
  std::string negative = lines[0] + "\n";
  for (size_t i = 1; i < lines.size(); ++i) {
    negative += "-" + std::to_string(lines.size() - i) + lines[i].substr(lines[i].find(',')) + "\n";
  }
  WriteFileAtomic(run + "/log.csv", negative);
  ExpectInputError([&] { ReadLogCsv(run + "/log.csv", 1.0); }, {"line 2", "negative"});
  // the run's own log is accepted: its last time is within the duration
  WriteFileAtomic(run + "/log.csv", original);
  const std::vector<LogRow> rows = ReadLogCsv(run + "/log.csv", 1.0);
  EXPECT_LE(rows.back().time_s, 1.0 + kLogTimeSlack_s);
  ExpectInputError([&] { ReadLogCsv(run + "/log.csv", 0.5); }, {"past the run's duration"});
}

// run.json's values are checked, each refusal naming run.json and the key.
TEST(ReplayTest, RunJsonValuesAreChecked) {
  const std::string run = HoverRun("run", 1.0);
  const nlohmann::json good = nlohmann::json::parse(ReadText(run + "/run.json"));
  // the scenario's own text with a seed out of its range
  std::string seed_minus_5 = good["scenario_text"];
  ASSERT_NE(seed_minus_5.find("seed: 1\n"), std::string::npos);
  seed_minus_5.replace(seed_minus_5.find("seed: 1\n"), 8, "seed: -5\n");
  const std::vector<std::tuple<std::string, nlohmann::json, std::string>> bad = {
      {"seed", -1, "whole number"},
      {"seed", 1.5, "whole number"},
      {"seed", 4294967296ULL, "whole number"},
      {"seed", "7", "whole number"},
      {"camera", "banana", "unknown camera 'banana'"},
      {"controller", "banana", "unknown controller 'banana'"},
      {"scenario_text", "name: [unclosed", "malformed YAML"},
      {"scenario_text", seed_minus_5, "seed"},
      {"sets", nlohmann::json::array({nlohmann::json::array({"duration", "-3"})}), "duration"},
      {"params_yaml", "quadrotor: [", "malformed YAML"}};
  for (const auto& [key, value, fragment] : bad) {
    SCOPED_TRACE(key + " = " + value.dump());
    nlohmann::json j = good;
    j[key] = value;
    WriteFileAtomic(run + "/run.json", j.dump(2));
    ExpectInputError([&] { ReadRunRecord(run); }, {"run.json: key '" + key + "'", fragment});
  }
  // the valid spellings: null overrides, the other camera, a registered controller
  nlohmann::json j = good;
  j["seed"] = 4294967295ULL;
  j["camera"] = nullptr;
  j["controller"] = "hpa_mpc";
  WriteFileAtomic(run + "/run.json", j.dump(2));
  const RunRecord record = ReadRunRecord(run);
  EXPECT_EQ(*record.seed, 4294967295UL);
  EXPECT_EQ(record.camera, "");
  EXPECT_EQ(ScenarioOf(record).controller.type, "hpa_mpc");
}

// A FIFO as run.json or log.csv, or a folder as log.csv, is refused at once as "not a regular
// file" (a FIFO with no writer blocked the replay forever; a folder was reported "empty").
TEST(ReplayTest, InputsThatAreNotRegularFilesAreRefused) {
  const std::string run = HoverRun("run", 1.0);
  const std::string log = ReadText(run + "/log.csv");
  const auto start = std::chrono::steady_clock::now();
  ReplayOptions options;
  options.dir = run;
  const auto replay = [&] { ReplayRun(options, [](const ReplayFrame&) {}); };
  std::remove((run + "/log.csv").c_str());
  ASSERT_EQ(mkfifo((run + "/log.csv").c_str(), 0600), 0);
  ExpectInputError(replay, {"log.csv", "not a regular file"});
  std::remove((run + "/log.csv").c_str());
  mkdir((run + "/log.csv").c_str(), 0755);
  ExpectInputError(replay, {"log.csv", "not a regular file"});
  rmdir((run + "/log.csv").c_str());
  WriteFileAtomic(run + "/log.csv", log);
  std::rename((run + "/run.json").c_str(), (run + "/run.json.real").c_str());
  ASSERT_EQ(mkfifo((run + "/run.json").c_str(), 0600), 0);
  ExpectInputError(replay, {"run.json", "not a regular file"});
  // all refused without waiting on a writer
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
}

// --rate NaN was taken (and the video writer then failed: exit 4): refused as bad input.
TEST(ReplayTest, ARateOutsideItsRangeIsRefused) {
  ReplayOptions options;
  options.dir = TestTempDir();  // never read: the rate is checked first
  for (double rate_hz : {std::nan(""), 0.5, 1e9, -30.0}) {
    options.rate_hz = rate_hz;
    ExpectInputError([&] { ReplayRun(options, [](const ReplayFrame&) {}); }, {"--rate"});
    ExpectInputError([&] { ReplayToVideo(options, TestTempDir() + "x.mp4"); }, {"--rate"});
  }
}

// run.json keeps the scenario's absolute path and the reference CSV's text: the run is rebuilt
// from another working directory after the CSV is gone, with the same samples.
TEST(ReplayTest, TheRecordKeepsTheReferenceCsv) {
  namespace fs = std::filesystem;
  const std::string dir = TestTempDir();
  fs::create_directories(dir + "scen/references");
  fs::copy_file(kScenarios + "csv_reference.yaml", dir + "scen/csv_reference.yaml");
  fs::copy_file(kScenarios + "references/figure_eight_path.csv",
                dir + "scen/references/figure_eight_path.csv");
  const std::string csv_text = ReadText(dir + "scen/references/figure_eight_path.csv");
  const fs::path cwd = fs::current_path();
  fs::current_path(dir);
  RunRecord record;
  record.scenario_file = "scen/csv_reference.yaml";  // relative, as typed on the command line
  record.scenario_text = ReadYamlFile(record.scenario_file);
  record.params = LoadParams(DefaultParamsPath());
  const Scenario flown = ScenarioOf(record);
  WriteRunRecord(dir, record);
  // the CSV gone, and read from elsewhere
  fs::remove(dir + "scen/references/figure_eight_path.csv");
  fs::current_path("/");
  const nlohmann::json j = nlohmann::json::parse(ReadText(dir + "run.json"));
  EXPECT_EQ(j["scenario_file"].get<std::string>(),
            fs::path(dir + "scen/csv_reference.yaml").lexically_normal().string());
  EXPECT_EQ(j["reference_csv_text"], csv_text);
  const Scenario rebuilt = ScenarioOf(ReadRunRecord(dir));
  fs::current_path(cwd);
  ASSERT_EQ(rebuilt.reference.samples.size(), flown.reference.samples.size());
  for (size_t i = 0; i < flown.reference.samples.size(); ++i) {
    EXPECT_EQ(rebuilt.reference.samples[i].p_WL_W, flown.reference.samples[i].p_WL_W);
    EXPECT_EQ(rebuilt.reference.samples[i].a_WL_W, flown.reference.samples[i].a_WL_W);
  }
  // a bad snapshot is refused naming run.json's key and the line
  nlohmann::json edited = j;
  edited["reference_csv_text"] = "t_s,x_m,y_m,z_m\n0,0,0,1\n0,1,0,1\n";
  WriteFileAtomic(dir + "run.json", edited.dump(2));
  ExpectInputError([&] { ReadRunRecord(dir); }, {"run.json: key 'reference_csv_text'", "line 3"});
}

// A replay stopped by a signal writes nothing: the previous video stays byte for byte and no
// partial file is left; a finished one replaces it whole.
TEST(ReplayTest, AStoppedReplayKeepsThePreviousVideo) {
  const std::string run = HoverRun("run", 3.0);
  const std::string video = run + "/replay.mp4";
  WriteFileAtomic(video, "the previous replay");
  ReplayOptions options;
  options.dir = run;
  // the stop arrives while frames are being written (the partial file exists)
  std::atomic<bool> done{false};
  std::thread signaller([&] {
    while (!done && !std::filesystem::exists(PartialPath(video))) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    RequestStop(SIGTERM);
  });
  const ReplaySummary stopped = ReplayToVideo(options, video);
  done = true;
  signaller.join();
  RequestStop(0);  // the flag is the process's: clear it for what follows
  EXPECT_EQ(stopped.stop_signal, SIGTERM);
  EXPECT_LT(stopped.frames, 91);  // 3 s at 30 Hz and t = 0: stopped before the end
  EXPECT_EQ(ReadText(video), "the previous replay");
  EXPECT_FALSE(std::filesystem::exists(PartialPath(video)));
  const ReplaySummary finished = ReplayToVideo(options, video);
  EXPECT_EQ(finished.stop_signal, 0);
  EXPECT_EQ(finished.frames, 91);
  EXPECT_GT(std::filesystem::file_size(video), 1000u);
  EXPECT_FALSE(std::filesystem::exists(PartialPath(video)));
}

}  // namespace
}  // namespace hpa
