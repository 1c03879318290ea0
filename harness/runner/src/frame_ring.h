#pragma once
// The shared-memory ring of rendered camera frames a separate flight stack reads (private to
// the runner; docs/protocol.md, hello's camera). The stack maps the same file, so it can shrink
// it under hpa: a write into pages past a file's end would kill hpa with SIGBUS. The ring is
// made read-only for others once sized, its size is checked (fstat) before every use, and a
// SIGBUS inside it (a shrink between that check and a write) is caught: the ring's pages are
// replaced by private zero pages so the write completes, and the next check ends the run.

#include <cstddef>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace hpa::runner {

/// One frame ring in /dev/shm: `slots` BGR frames of width_px x height_px, rows packed.
class FrameRing {
 public:
  /// Creates, sizes and maps the ring `name` ("/NAME"); throws flight::ProtocolError naming it
  /// when it cannot.
  FrameRing(const std::string& name, int slots, int width_px, int height_px);
  /// Unmaps and removes the ring.
  ~FrameRing();
  FrameRing(const FrameRing&) = delete;
  FrameRing& operator=(const FrameRing&) = delete;

  /// Throws flight::ProtocolError naming the ring when its file has shrunk below the mapping
  /// (or a write past its end was caught): nothing may be written into it or sent from it.
  void Check() const;
  /// The image of slot `i` (a view of the ring's memory; Check before writing into it).
  cv::Mat* Slot(int i) { return &slot_mats_[static_cast<size_t>(i)]; }
  /// The ring's POSIX shared-memory name ("/NAME").
  const std::string& name() const { return name_; }
  /// Bytes of one slot.
  size_t slot_bytes() const { return slot_bytes_; }

 private:
  std::string name_;
  int fd_ = -1;                    // kept open: fstat tells whether the file shrank
  unsigned char* base_ = nullptr;  // the mapping (bytes_ long)
  size_t slot_bytes_ = 0, bytes_ = 0;
  int guard_ = -1;  // its entry in the SIGBUS handler's table (-1: none free)
  std::vector<cv::Mat> slot_mats_;
};

}  // namespace hpa::runner
