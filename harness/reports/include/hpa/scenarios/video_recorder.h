#pragma once
// MP4 of a run: chase camera with the onboard payload-camera image inset and a heads-up line.

#include <deque>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "hpa/models/state.h"
#include "hpa/scenarios/runner.h"

namespace hpa {

class VideoSink;

/// Checks a video path before anything is rendered: a .mp4 name in a folder that exists (else
/// InputError naming `option` and saying whether the folder or the extension is the problem),
/// and a folder that can be written with no folder in the way (else OutputError: exit 4).
void CheckVideoPath(const std::string& path, const std::string& option = "--video");

/// Writes frames through OpenCV's video writer (H.264 "avc1", else "mp4v"); optionally only
/// around slack events. The file is written whole or not at all: frames go to
/// PartialPath(path), which Finish() renames onto `path`; a recorder destroyed or abandoned
/// before that removes the partial file and leaves a previous video at `path` as it was.
class VideoRecorder {
 public:
  static constexpr int kWidthPx = 960;
  static constexpr int kHeightPx = 540;
  static constexpr double kSlackWindow_s = 1.0;  // kept before and after each slack event

  /// What the heads-up line shows.
  struct Hud {
    double time_s;
    CableMode true_mode;
    CableMode estimated_mode;
    double thrust_N;
    double tension_N;
  };

  /// What a team's heads-up lines show (docs/cooperative.md).
  struct TeamHud {
    /// One vehicle's cable.
    struct Cable {
      double tension_N = 0.0;                  // true tension
      CableMode true_mode = CableMode::kTaut;  // true mode
      std::optional<bool> taut_seen;           // its controller's reading (none before its first)
    };
    double time_s = 0.0;                    // the video tick's simulated time
    std::optional<double> payload_error_m;  // |payload - reference| (none before the first row)
    std::vector<Cable> cables;              // (N)
  };

  /// Checks `path` (CheckVideoPath, naming `option`) and opens its partial file; throws
  /// InputError or OutputError as CheckVideoPath does, OutputError if no writer opens it.
  VideoRecorder(const std::string& path, double rate_hz, bool slack_events_only,
                const std::string& option = "--video");
  /// Removes the partial file unless Finish() has committed it.
  ~VideoRecorder();

  /// Adds one frame (chase view kWidthPx x kHeightPx, onboard frame any size, BGR).
  void AddFrame(const cv::Mat& chase_bgr, const cv::Mat& onboard_bgr, const Hud& hud);

  /// Adds one frame of a team (chase view kWidthPx x kHeightPx; each vehicle's onboard frame,
  /// any size, as an inset down the right side framed in `inset_colors_bgr`'s colour). A
  /// slack-events video keeps the frames around any cable's slack event.
  void AddTeamFrame(const cv::Mat& chase_bgr, const std::vector<cv::Mat>& onboard_bgr,
                    const std::vector<cv::Scalar>& inset_colors_bgr, const TeamHud& hud);

  /// Flushes, closes and renames the partial file onto the path; returns the number of frames
  /// written. A slack-events video with no frame is not written (and a previous one at the path
  /// removed: it belongs to another run). Throws OutputError if the file cannot be completed.
  int Finish();

  /// Closes and removes the partial file (a stopped replay): the path keeps what it held.
  void Abandon();

  /// The codec the file is written with: "avc1" (H.264) or "mp4v".
  const std::string& codec() const { return codec_; }

 private:
  cv::Mat Compose(const cv::Mat& chase_bgr, const cv::Mat& onboard_bgr, const Hud& hud) const;
  cv::Mat ComposeTeam(const cv::Mat& chase_bgr, const std::vector<cv::Mat>& onboard_bgr,
                      const std::vector<cv::Scalar>& inset_colors_bgr, const TeamHud& hud) const;
  // writes a composed frame, or (slack_events_only) keeps it for a slack event's window
  void Keep(const cv::Mat& frame, double time_s, bool slack);

  // closes the writer and removes the partial file (Abandon and the destructor)
  void RemovePartial();

  std::string path_;
  std::string codec_;
  std::unique_ptr<VideoSink> writer_;  // OpenCV's video writer, in the media module
  double rate_hz_;
  bool slack_events_only_;
  std::deque<cv::Mat> pre_buffer_;  // frames before a slack event (slack_events_only)
  double keep_until_s_ = -1.0;      // write frames up to this time
  int frames_written_ = 0;
  bool done_ = false;  // Finish() or Abandon() has run: nothing left to clean up
};

/// The video of a run as a recorder: the chase camera and a whole onboard frame of its own at
/// each video tick. It never reads or changes what the loop's camera path uses (its region, its
/// frames), so a run with a video is the run without one. Pass it in RunOptions::recorders and
/// call Finish() after the run.
class VideoTickRecorder final : public RunRecorder {
 public:
  /// Writes `path` at rate_hz (RateTable::video), optionally only around slack events.
  VideoTickRecorder(const std::string& path, double rate_hz, bool slack_events_only)
      : video_(path, rate_hz, slack_events_only), rate_hz_(rate_hz) {}
  void OnVideoTick(sim::World& world, const LogRow& now, const cv::Mat& onboard) override;
  /// A team's frame: its chase camera with every vehicle's onboard camera as an inset and the
  /// heads-up lines (time, payload error, each cable's tension and mode) from the world's truth
  /// now and the latest log row.
  void OnTeamVideoTick(sim::TeamWorld& world, const TeamLogRow* latest) override;
  double video_rate_hz() const override { return rate_hz_; }
  /// Flushes and closes the file (VideoRecorder::Finish).
  int Finish() { return video_.Finish(); }

 private:
  VideoRecorder video_;
  double rate_hz_;
  cv::Mat onboard_;                    // the whole onboard frame of the latest video tick
  cv::Mat chase_;                      // a team's chase frame of the latest video tick
  std::vector<cv::Mat> team_onboard_;  // each vehicle's onboard frame of the latest tick (N)
};

}  // namespace hpa
