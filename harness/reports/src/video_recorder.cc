#include "hpa/scenarios/video_recorder.h"

#include <unistd.h>

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "hpa/scenarios/metrics.h"
#include "hpa/sim/team_world.h"
#include "hpa/sim/world.h"
#include "media.h"

namespace hpa {

void CheckVideoPath(const std::string& path, const std::string& option) {
  namespace fs = std::filesystem;
  const fs::path file(path);
  std::string extension = file.extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (extension != ".mp4") {
    throw InputError(path, option,
                     "the extension is the problem: expected a file name ending in .mp4, got '" +
                         file.extension().string() + "'");
  }
  const fs::path folder = file.has_parent_path() ? file.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) {
    throw InputError(
        path, option,
        "the folder is the problem: '" + folder.string() + "' is not a folder that exists");
  }
  // the folder is there but cannot take the file: an output that cannot be written (exit 4)
  if (access(folder.c_str(), W_OK) != 0) {
    throw OutputError(path,
                      "the folder '" + folder.string() + "' is not writable (" + option + ")");
  }
  if (fs::is_directory(file, ec)) {
    throw OutputError(path, "a folder of that name is in the way (" + option + ")");
  }
}

VideoRecorder::VideoRecorder(const std::string& path, double rate_hz, bool slack_events_only,
                             const std::string& option)
    : path_(path), rate_hz_(rate_hz), slack_events_only_(slack_events_only) {
  CheckVideoPath(path, option);
  // written under the partial name (same folder, still .mp4 for the writer's container choice)
  const std::string partial = PartialPath(path);
  // H.264 (plays in browsers and slides, files several times smaller); MPEG-4 part 2 where the
  // OpenCV build has no H.264 encoder
  writer_ = OpenVideo(partial, "avc1", rate_hz, cv::Size(kWidthPx, kHeightPx));
  codec_ = "avc1";
  if (writer_ == nullptr) {
    writer_ = OpenVideo(partial, "mp4v", rate_hz, cv::Size(kWidthPx, kHeightPx));
    codec_ = "mp4v";
  }
  if (writer_ == nullptr) {
    std::remove(partial.c_str());
    throw OutputError(path, "no MP4 writer could open it (the folder and the .mp4 name are fine)");
  }
}

VideoRecorder::~VideoRecorder() {
  if (done_) return;
  try {
    RemovePartial();
  } catch (...) {
    // a destructor must not throw; the partial file is at worst left behind
  }
}

void VideoRecorder::RemovePartial() {
  done_ = true;
  if (writer_ != nullptr) writer_->Close();
  std::remove(PartialPath(path_).c_str());
}

void VideoRecorder::Abandon() {
  if (!done_) RemovePartial();
}

cv::Mat VideoRecorder::Compose(const cv::Mat& chase_bgr, const cv::Mat& onboard_bgr,
                               const Hud& hud) const {
  cv::Mat frame;
  cv::resize(chase_bgr, frame, cv::Size(kWidthPx, kHeightPx));
  // onboard inset, top right, a third of the width
  if (!onboard_bgr.empty()) {
    const int w = kWidthPx / 3;
    const int h = w * onboard_bgr.rows / onboard_bgr.cols;
    cv::Mat inset;
    cv::resize(onboard_bgr, inset, cv::Size(w, h), 0, 0, cv::INTER_AREA);
    const cv::Rect roi(kWidthPx - w - 8, 8, w, h);
    inset.copyTo(frame(roi));
    cv::rectangle(frame, roi, cv::Scalar(255, 255, 255), 1);
  }
  // heads-up line; the whole bar turns orange while the cable is truly slack
  const bool slack = hud.true_mode == CableMode::kSlack;
  cv::rectangle(frame, cv::Rect(0, kHeightPx - 34, kWidthPx, 34),
                slack ? cv::Scalar(0, 140, 255) : cv::Scalar(40, 40, 40), cv::FILLED);
  char text[200];
  std::snprintf(text, sizeof(text), "t %6.2f s   true %-5s   est %-5s   thrust %5.2f N   T %5.2f N",
                hud.time_s, ToString(hud.true_mode), ToString(hud.estimated_mode), hud.thrust_N,
                hud.tension_N);
  cv::putText(frame, text, cv::Point(10, kHeightPx - 10), cv::FONT_HERSHEY_SIMPLEX, 0.65,
              cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  return frame;
}

void VideoRecorder::AddFrame(const cv::Mat& chase_bgr, const cv::Mat& onboard_bgr, const Hud& hud) {
  Keep(Compose(chase_bgr, onboard_bgr, hud), hud.time_s, hud.true_mode == CableMode::kSlack);
}

cv::Mat VideoRecorder::ComposeTeam(const cv::Mat& chase_bgr,
                                   const std::vector<cv::Mat>& onboard_bgr,
                                   const std::vector<cv::Scalar>& inset_colors_bgr,
                                   const TeamHud& hud) const {
  constexpr int kBarPx = 56;  // two heads-up lines
  cv::Mat frame;
  cv::resize(chase_bgr, frame, cv::Size(kWidthPx, kHeightPx));
  // onboard insets down the right side, a quarter of the width each, framed in the vehicle's
  // colour and labelled with its index
  const int w = kWidthPx / 4;
  int top = 8;
  for (size_t i = 0; i < onboard_bgr.size(); ++i) {
    if (onboard_bgr[i].empty()) continue;
    const int h = w * onboard_bgr[i].rows / onboard_bgr[i].cols;
    if (top + h > kHeightPx - kBarPx) break;
    cv::Mat inset;
    cv::resize(onboard_bgr[i], inset, cv::Size(w, h), 0, 0, cv::INTER_AREA);
    const cv::Rect roi(kWidthPx - w - 8, top, w, h);
    inset.copyTo(frame(roi));
    const cv::Scalar colour =
        i < inset_colors_bgr.size() ? inset_colors_bgr[i] : cv::Scalar(255, 255, 255);
    cv::rectangle(frame, roi, colour, 2);
    cv::putText(frame, std::to_string(i), cv::Point(roi.x + 6, roi.y + 20),
                cv::FONT_HERSHEY_SIMPLEX, 0.6, colour, 2, cv::LINE_AA);
    top += h + 8;
  }
  // heads-up lines; the whole bar turns orange while any cable is truly slack
  bool slack = false;
  for (const TeamHud::Cable& c : hud.cables) slack = slack || c.true_mode == CableMode::kSlack;
  cv::rectangle(frame, cv::Rect(0, kHeightPx - kBarPx, kWidthPx, kBarPx),
                slack ? cv::Scalar(0, 140, 255) : cv::Scalar(40, 40, 40), cv::FILLED);
  char text[200];
  if (hud.payload_error_m) {
    std::snprintf(text, sizeof(text), "t %6.2f s   payload error %6.3f m", hud.time_s,
                  *hud.payload_error_m);
  } else {
    std::snprintf(text, sizeof(text), "t %6.2f s   payload error --", hud.time_s);
  }
  cv::putText(frame, text, cv::Point(10, kHeightPx - 34), cv::FONT_HERSHEY_SIMPLEX, 0.6,
              cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  std::string cables;
  for (size_t i = 0; i < hud.cables.size(); ++i) {
    const TeamHud::Cable& c = hud.cables[i];
    // the controller's reading only where it differs from the truth
    const bool seen_differs = c.taut_seen && *c.taut_seen != (c.true_mode == CableMode::kTaut);
    std::snprintf(text, sizeof(text), "%scable %zu %-5s T %6.2f N%s", i ? "   " : "", i,
                  ToString(c.true_mode), c.tension_N,
                  seen_differs ? (*c.taut_seen ? " (seen taut)" : " (seen slack)") : "");
    cables += text;
  }
  cv::putText(frame, cables, cv::Point(10, kHeightPx - 10), cv::FONT_HERSHEY_SIMPLEX, 0.6,
              cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  return frame;
}

void VideoRecorder::AddTeamFrame(const cv::Mat& chase_bgr, const std::vector<cv::Mat>& onboard_bgr,
                                 const std::vector<cv::Scalar>& inset_colors_bgr,
                                 const TeamHud& hud) {
  bool slack = false;
  for (const TeamHud::Cable& c : hud.cables) slack = slack || c.true_mode == CableMode::kSlack;
  Keep(ComposeTeam(chase_bgr, onboard_bgr, inset_colors_bgr, hud), hud.time_s, slack);
}

void VideoRecorder::Keep(const cv::Mat& frame, double time_s, bool slack) {
  if (!slack_events_only_) {
    writer_->Write(frame);
    ++frames_written_;
    return;
  }
  if (slack) {
    // flush what led up to the event, then keep a window after it ends
    for (const cv::Mat& f : pre_buffer_) {
      writer_->Write(f);
      ++frames_written_;
    }
    pre_buffer_.clear();
    keep_until_s_ = time_s + kSlackWindow_s;
  }
  if (time_s <= keep_until_s_) {
    writer_->Write(frame);
    ++frames_written_;
    return;
  }
  pre_buffer_.push_back(frame);
  while (pre_buffer_.size() > static_cast<size_t>(kSlackWindow_s * rate_hz_)) {
    pre_buffer_.pop_front();
  }
}

int VideoRecorder::Finish() {
  if (done_) return frames_written_;
  // a slack-events video of a run without slack would be an empty file: write nothing
  if (slack_events_only_ && frames_written_ == 0) {
    RemovePartial();
    std::remove(path_.c_str());
    return 0;
  }
  done_ = true;
  writer_->Close();
  std::error_code ec;
  if (std::filesystem::file_size(PartialPath(path_), ec) == 0 || ec) {
    std::remove(PartialPath(path_).c_str());
    throw OutputError(path_, "the video writer left no file (disk full?)");
  }
  CommitPartial(path_);
  return frames_written_;
}

void VideoTickRecorder::OnVideoTick(sim::World& world, const LogRow& now, const cv::Mat& onboard) {
  (void)onboard;
  world.renderer().RenderPayloadCamera(&onboard_, cv::Rect());
  VideoRecorder::Hud hud{now.time_s, now.truth.mode, now.estimate.mode, now.command.thrust_N,
                         now.cable_tension_N};
  video_.AddFrame(
      world.renderer().RenderChaseCamera(VideoRecorder::kWidthPx, VideoRecorder::kHeightPx),
      onboard_, hud);
}

void VideoTickRecorder::OnTeamVideoTick(sim::TeamWorld& world, const TeamLogRow* latest) {
  sim::TeamRenderer& renderer = world.renderer();
  const int n = world.VehicleCount();
  renderer.RenderChaseCamera(VideoRecorder::kWidthPx, VideoRecorder::kHeightPx, &chase_);
  team_onboard_.resize(static_cast<size_t>(n));
  std::vector<cv::Scalar> colours;
  for (int i = 0; i < n; ++i) {
    renderer.RenderOnboardCamera(i, sim::TeamRenderer::kOnboardWidthPx,
                                 sim::TeamRenderer::kOnboardHeightPx,
                                 &team_onboard_[static_cast<size_t>(i)]);
    colours.push_back(renderer.VehicleColorBgr(i));
  }
  // the cables as they are now; the payload error and the controllers' readings of the latest
  // control step
  const sim::TeamTruth truth = world.GetTruth();
  VideoRecorder::TeamHud hud;
  hud.time_s = truth.time_s;
  if (latest != nullptr) {
    hud.payload_error_m = (latest->x_true.head<3>() - latest->reference.p_WL_W).norm();
  }
  for (int i = 0; i < n; ++i) {
    const size_t k = static_cast<size_t>(i);
    VideoRecorder::TeamHud::Cable c;
    c.tension_N = truth.cable_tension_N[k];
    c.true_mode = truth.modes[k];
    if (latest != nullptr && k < latest->vehicles.size())
      c.taut_seen = latest->vehicles[k].taut_seen;
    hud.cables.push_back(c);
  }
  video_.AddTeamFrame(chase_, team_onboard_, colours, hud);
}

}  // namespace hpa
