#include "harness/runner/src/frame_ring.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <mutex>

#include "hpa/flight/protocol.h"

namespace hpa::runner {
namespace {

// A mapped ring as the SIGBUS handler sees it (atomics: the handler may run on any thread).
struct GuardedRing {
  std::atomic<uintptr_t> base{0};  // 0: entry free
  std::atomic<size_t> bytes{0};
  std::atomic<bool> truncated{false};  // a write past the file's end was caught
};
// a process maps one ring per run (hpa run, each sweep worker); room for a few at once
GuardedRing g_rings[8];
struct sigaction g_previous_sigbus;  // the handler before ours, for faults outside the rings

// SIGBUS: inside a ring, the file shrank under the mapping; its pages become private zero pages
// (the faulting access then completes) and the ring is marked for its next Check. Elsewhere, what
// would have happened without this handler.
void OnSigbus(int signal_number, siginfo_t* info, void* context) {
  const auto address = reinterpret_cast<uintptr_t>(info->si_addr);
  for (GuardedRing& ring : g_rings) {
    const uintptr_t base = ring.base.load();
    const size_t bytes = ring.bytes.load();
    if (base == 0 || address < base || address >= base + bytes) continue;
    void* p = ::mmap(reinterpret_cast<void*>(base), bytes, PROT_READ | PROT_WRITE,
                     MAP_PRIVATE | MAP_ANONYMOUS | MAP_FIXED, -1, 0);
    if (p != MAP_FAILED) {
      ring.truncated.store(true);
      return;
    }
    break;  // cannot replace the pages: the default action below
  }
  if ((g_previous_sigbus.sa_flags & SA_SIGINFO) != 0 && g_previous_sigbus.sa_sigaction != nullptr) {
    g_previous_sigbus.sa_sigaction(signal_number, info, context);
  } else if (g_previous_sigbus.sa_handler != SIG_DFL && g_previous_sigbus.sa_handler != SIG_IGN) {
    g_previous_sigbus.sa_handler(signal_number);
  } else {
    // the default action: returning re-runs the faulting access, which now ends the process
    struct sigaction dfl {};
    dfl.sa_handler = SIG_DFL;
    ::sigaction(SIGBUS, &dfl, nullptr);
  }
}

// Installs OnSigbus once per process.
void InstallSigbusHandler() {
  static std::once_flag once;
  std::call_once(once, [] {
    struct sigaction action {};
    action.sa_sigaction = OnSigbus;
    action.sa_flags = SA_SIGINFO;
    sigemptyset(&action.sa_mask);
    ::sigaction(SIGBUS, &action, &g_previous_sigbus);
  });
}

// Claims a free entry of g_rings for [base, base + bytes); -1 when none is free.
int GuardRing(unsigned char* base, size_t bytes) {
  InstallSigbusHandler();
  for (int i = 0; i < static_cast<int>(std::size(g_rings)); ++i) {
    uintptr_t expected = 0;
    if (g_rings[i].base.compare_exchange_strong(expected, reinterpret_cast<uintptr_t>(base))) {
      g_rings[i].truncated.store(false);
      g_rings[i].bytes.store(bytes);
      return i;
    }
  }
  return -1;
}

[[noreturn]] void Fail(const std::string& what) { throw flight::ProtocolError(what); }

}  // namespace

FrameRing::FrameRing(const std::string& name, int slots, int width_px, int height_px)
    : name_(name) {
  slot_bytes_ = static_cast<size_t>(width_px) * static_cast<size_t>(height_px) * 3;
  bytes_ = slot_bytes_ * static_cast<size_t>(slots);
  fd_ = ::shm_open(name_.c_str(), O_CREAT | O_EXCL | O_RDWR | O_CLOEXEC, 0600);
  if (fd_ < 0) Fail("shm_open " + name_ + ": " + std::strerror(errno));
  // sized, then read-only for everyone else (the stack maps it to read): a stack cannot shrink
  // it by mistake (this descriptor keeps writing)
  if (::ftruncate(fd_, static_cast<off_t>(bytes_)) != 0 || ::fchmod(fd_, 0400) != 0) {
    const std::string why = std::strerror(errno);
    ::close(fd_);
    ::shm_unlink(name_.c_str());
    Fail("cannot size the frame ring " + name_ + ": " + why);
  }
  void* p = ::mmap(nullptr, bytes_, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, 0);
  if (p == MAP_FAILED) {
    const std::string why = std::strerror(errno);
    ::close(fd_);
    ::shm_unlink(name_.c_str());
    Fail("cannot map the frame ring " + name_ + ": " + why);
  }
  base_ = static_cast<unsigned char*>(p);
  guard_ = GuardRing(base_, bytes_);
  for (int i = 0; i < slots; ++i) {
    slot_mats_.emplace_back(height_px, width_px, CV_8UC3,
                            base_ + slot_bytes_ * static_cast<size_t>(i));
  }
}

FrameRing::~FrameRing() {
  if (guard_ >= 0) g_rings[guard_].base.store(0);
  ::munmap(base_, bytes_);
  ::close(fd_);
  ::shm_unlink(name_.c_str());
}

void FrameRing::Check() const {
  if (guard_ >= 0 && g_rings[guard_].truncated.load()) {
    Fail("the frame ring " + name_ + " was cut short while hpa wrote a frame into it");
  }
  struct stat st {};
  if (::fstat(fd_, &st) != 0) {
    Fail("cannot check the frame ring " + name_ + ": " + std::strerror(errno));
  }
  if (static_cast<uint64_t>(st.st_size) < bytes_) {
    Fail("the frame ring " + name_ + " shrank to " + std::to_string(st.st_size) + " bytes (" +
         std::to_string(bytes_) + " mapped): something truncated it");
  }
}

}  // namespace hpa::runner
