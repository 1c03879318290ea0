#pragma once
// Image and video files. OpenCV's imgcodecs and videoio bring FFmpeg, GStreamer, GDAL and about
// two hundred shared libraries more, whose loading and relocation would cost every process that
// links them a large part of a second at start: they live in a module (libhpa_media.so, built
// from src/media_module/) that a process loads when it first writes an image or a video, so a
// run, a sweep worker or a test that writes neither never loads them.

#include <memory>
#include <opencv2/core.hpp>
#include <string>

namespace hpa {

/// An open video file.
class VideoSink {
 public:
  virtual ~VideoSink() = default;
  /// Appends one BGR frame of the size the file was opened with.
  virtual void Write(const cv::Mat& bgr) = 0;
  /// Flushes and closes the file.
  virtual void Close() = 0;
};

/// What the module provides; its one exported symbol, hpa_media_module(), returns it.
struct MediaModule {
  int abi_version = 0;  // kMediaModuleAbiVersion of the build that made the module
  /// A video of frame_size at rate_hz with the codec `fourcc` (e.g. "avc1", "mp4v"); nullptr if
  /// no writer opens it.
  VideoSink* (*open_video)(const std::string& path, const char* fourcc, double rate_hz,
                           cv::Size frame_size) = nullptr;
  /// cv::imwrite; false if the image could not be written or the extension is not one it encodes.
  bool (*write_image)(const std::string& path, const cv::Mat& image) = nullptr;
};

/// Changes whenever MediaModule changes: a module of another build is refused.
constexpr int kMediaModuleAbiVersion = 1;

/// The module's exported entry point's name.
constexpr const char* kMediaModuleSymbol = "hpa_media_module";

/// Opens a video through the module (MediaModule::open_video). Throws OutputError naming `path`
/// if the module cannot be loaded (where it was looked for and why it failed).
std::unique_ptr<VideoSink> OpenVideo(const std::string& path, const char* fourcc, double rate_hz,
                                     cv::Size frame_size);

/// Writes an image file through the module (MediaModule::write_image); throws OutputError as
/// OpenVideo does.
bool WriteImage(const std::string& path, const cv::Mat& image);

}  // namespace hpa
