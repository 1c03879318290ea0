// libhpa_media.so: image and video files through OpenCV's imgcodecs and videoio, loaded by
// harness/reports/src/media.cc when a process first writes one (see media.h for why).
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <string>

#include "harness/reports/src/media.h"

namespace hpa {
namespace {

// A video file through cv::VideoWriter.
class OpenCvVideoSink final : public VideoSink {
 public:
  explicit OpenCvVideoSink(cv::VideoWriter writer) : writer_(std::move(writer)) {}
  void Write(const cv::Mat& bgr) override { writer_.write(bgr); }
  void Close() override { writer_.release(); }

 private:
  cv::VideoWriter writer_;
};

VideoSink* OpenVideoFile(const std::string& path, const char* fourcc, double rate_hz,
                         cv::Size frame_size) {
  cv::VideoWriter writer;
  try {
    writer.open(path, cv::VideoWriter::fourcc(fourcc[0], fourcc[1], fourcc[2], fourcc[3]), rate_hz,
                frame_size);
  } catch (const cv::Exception&) {
    return nullptr;
  }
  if (!writer.isOpened()) return nullptr;
  return new OpenCvVideoSink(std::move(writer));
}

bool WriteImageFile(const std::string& path, const cv::Mat& image) {
  try {
    return cv::imwrite(path, image);
  } catch (const cv::Exception&) {
    return false;  // e.g. an extension OpenCV cannot encode
  }
}

}  // namespace
}  // namespace hpa

/// The module's entry point (media.h).
extern "C" __attribute__((visibility("default"))) const hpa::MediaModule* hpa_media_module() {
  static const hpa::MediaModule module = [] {
    hpa::MediaModule m;
    m.abi_version = hpa::kMediaModuleAbiVersion;
    m.open_video = hpa::OpenVideoFile;
    m.write_image = hpa::WriteImageFile;
    return m;
  }();
  return &module;
}
