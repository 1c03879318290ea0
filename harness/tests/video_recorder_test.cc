// CheckVideoPath's refusals and VideoRecorder: every frame written, or only the frames within
// kSlackWindow_s of a slack event, no file left for a slack-events video without slack, and a
// video that appears whole or not at all.

#include "hpa/scenarios/video_recorder.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <opencv2/videoio.hpp>
#include <string>

#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "models/tests/temp_dir.h"

namespace hpa {
namespace {

// 8 Hz: frame times k / 8 s are exact in binary, so the window's end is no rounding question.
constexpr double kRate_Hz = 8.0;

long FileSize(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  return in ? static_cast<long>(in.tellg()) : -1;
}

// Adds frames k = 0 .. count - 1 at k / kRate_Hz, truly slack for k in [slack_from, slack_to].
void AddFrames(VideoRecorder* video, int count, int slack_from, int slack_to) {
  const cv::Mat chase(VideoRecorder::kHeightPx, VideoRecorder::kWidthPx, CV_8UC3,
                      cv::Scalar(90, 120, 150));
  const cv::Mat onboard(48, 64, CV_8UC3, cv::Scalar(20, 20, 200));
  for (int k = 0; k < count; ++k) {
    const bool slack = k >= slack_from && k <= slack_to;
    const CableMode mode = slack ? CableMode::kSlack : CableMode::kTaut;
    video->AddFrame(chase, onboard, {k / kRate_Hz, mode, mode, 8.0, slack ? 0.0 : 1.0});
  }
}

TEST(VideoRecorderTest, CheckVideoPathNamesTheProblem) {
  const std::string dir = TestTempDir();
  EXPECT_NO_THROW(CheckVideoPath(dir + "run.mp4"));
  EXPECT_NO_THROW(CheckVideoPath(dir + "run.MP4"));  // the extension in any case
  try {
    CheckVideoPath(dir + "run.avi");
    FAIL() << ".avi was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "--video");
    EXPECT_NE(std::string(e.what()).find("extension"), std::string::npos) << e.what();
  }
  try {
    CheckVideoPath(dir + "missing/run.mp4");
    FAIL() << "a missing folder was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("folder"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(dir + "missing"), std::string::npos) << e.what();
  }
  // a folder in the way cannot be written over: an output error (exit 4), naming the option
  mkdir((dir + "taken.mp4").c_str(), 0755);
  try {
    CheckVideoPath(dir + "taken.mp4", "--out");
    FAIL() << "a folder in the way was accepted";
  } catch (const OutputError& e) {
    EXPECT_NE(std::string(e.what()).find("in the way (--out)"), std::string::npos) << e.what();
  }
}

// A recorder destroyed or abandoned before Finish() leaves the previous file as it was and no
// partial file; Finish() replaces it whole.
TEST(VideoRecorderTest, OnlyAFinishedVideoReplacesThePreviousOne) {
  const std::string path = TestTempDir() + "video.mp4";
  std::ofstream(path) << "previous";
  {
    VideoRecorder video(path, kRate_Hz, false);
    AddFrames(&video, 4, 100, 100);
    EXPECT_GT(FileSize(PartialPath(path)), -1);  // the frames go to the partial file
  }
  EXPECT_EQ(FileSize(path), 8);  // "previous"
  EXPECT_EQ(FileSize(PartialPath(path)), -1);
  VideoRecorder abandoned(path, kRate_Hz, false);
  AddFrames(&abandoned, 4, 100, 100);
  abandoned.Abandon();
  EXPECT_EQ(FileSize(path), 8);
  EXPECT_EQ(FileSize(PartialPath(path)), -1);
  VideoRecorder finished(path, kRate_Hz, false);
  AddFrames(&finished, 4, 100, 100);
  EXPECT_EQ(finished.Finish(), 4);
  EXPECT_GT(FileSize(path), 8);
  EXPECT_EQ(FileSize(PartialPath(path)), -1);
  cv::VideoCapture read_back(path);
  ASSERT_TRUE(read_back.isOpened());
  EXPECT_EQ(read_back.get(cv::CAP_PROP_FRAME_COUNT), 4);
}

TEST(VideoRecorderTest, EveryFrameIsWritten) {
  const std::string path = TestTempDir() + "all.mp4";
  VideoRecorder video(path, kRate_Hz, false);
  AddFrames(&video, 12, 100, 100);  // never slack
  EXPECT_EQ(video.Finish(), 12);
  EXPECT_TRUE(video.codec() == "avc1" || video.codec() == "mp4v") << video.codec();
  EXPECT_GT(FileSize(path), 0);
}

TEST(VideoRecorderTest, SlackEventsOnlyKeepsAWindowAroundTheEvent) {
  const std::string path = TestTempDir() + "slack.mp4";
  VideoRecorder video(path, kRate_Hz, true);
  // slack at frames 16..18 (2.0 .. 2.25 s) of 40: the 8 frames (1 s) before it, its 3, and the
  // 8 after it up to 2.25 + 1 = 3.25 s inclusive (frames 19..26); nothing else
  AddFrames(&video, 40, 16, 18);
  EXPECT_EQ(video.Finish(), 8 + 3 + 8);
  EXPECT_GT(FileSize(path), 0);
  cv::VideoCapture read_back(path);
  ASSERT_TRUE(read_back.isOpened());
  EXPECT_EQ(read_back.get(cv::CAP_PROP_FRAME_COUNT), 8 + 3 + 8);
}

TEST(VideoRecorderTest, SlackEventsOnlyWithoutSlackLeavesNoFile) {
  const std::string path = TestTempDir() + "none.mp4";
  VideoRecorder video(path, kRate_Hz, true);
  AddFrames(&video, 20, 100, 100);
  EXPECT_EQ(video.Finish(), 0);
  EXPECT_EQ(FileSize(path), -1);
}

TEST(VideoRecorderTest, UnwritablePathIsRefusedBeforeRecording) {
  EXPECT_THROW(VideoRecorder(TestTempDir() + "missing/run.mp4", kRate_Hz, false), InputError);
}

}  // namespace
}  // namespace hpa
