#include "hpa/scenarios/video_recorder.h"

#include <unistd.h>

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
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
  cv::Mat frame = Compose(chase_bgr, onboard_bgr, hud);
  if (!slack_events_only_) {
    writer_->Write(frame);
    ++frames_written_;
    return;
  }
  if (hud.true_mode == CableMode::kSlack) {
    // flush what led up to the event, then keep a window after it ends
    for (const cv::Mat& f : pre_buffer_) {
      writer_->Write(f);
      ++frames_written_;
    }
    pre_buffer_.clear();
    keep_until_s_ = hud.time_s + kSlackWindow_s;
  }
  if (hud.time_s <= keep_until_s_) {
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
  video_.AddFrame(world.renderer().RenderChaseCamera(VideoRecorder::kWidthPx, VideoRecorder::kHeightPx),
                  onboard_, hud);
}

}  // namespace hpa
