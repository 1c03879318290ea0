// What a separate flight stack shares with hpa, on hostile ground: a frame ring the stack cuts
// short ends the run with an error instead of killing hpa with SIGBUS, and what a killed hpa
// left behind (socket folder, ring, stack processes) is reclaimed by the next one.

#include "harness/runner/src/flight_process.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>

#include "hpa/flight/protocol.h"
#include "harness/runner/src/frame_ring.h"

namespace hpa::runner {
namespace {

// The text of the ProtocolError `f` throws ("" when it throws none).
template <class F>
std::string ErrorOf(F&& f) {
  try {
    f();
  } catch (const flight::ProtocolError& e) {
    return e.what();
  }
  return "";
}

// Whether `path` exists.
bool Exists(const std::string& path) {
  struct stat st {};
  return ::lstat(path.c_str(), &st) == 0;
}

// Whether process `pid` (a child of this one) has ended, waiting up to 2 s.
bool Ended(pid_t pid) {
  for (int i = 0; i < 400; ++i) {
    if (::waitpid(pid, nullptr, WNOHANG) == pid) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

// Waits up to 2 s for process `pid` to run `program` (it has left fork for exec: its
// environment is the stack's own).
bool Runs(pid_t pid, const std::string& program) {
  for (int i = 0; i < 400; ++i) {
    FILE* f = std::fopen(("/proc/" + std::to_string(pid) + "/cmdline").c_str(), "r");
    char text[64] = {};
    if (f != nullptr) {
      const size_t n = std::fread(text, 1, sizeof text - 1, f);
      std::fclose(f);
      if (std::string(text, n).rfind(program, 0) == 0) return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

// A ring shrunk under the mapping is found before the next use, and a write into it after the
// shrink (the race a check cannot close) completes instead of raising SIGBUS.
TEST(FrameRingTest, ARingCutShortEndsTheRunInsteadOfKillingHpa) {
  const std::string name = "/hpa-flight-test-" + std::to_string(::getpid());
  FrameRing ring(name, 2, 64, 48);
  EXPECT_EQ(ErrorOf([&] { ring.Check(); }), "");
  ring.Slot(1)->setTo(cv::Scalar(1, 2, 3));
  // others may only read it
  struct stat st {};
  ASSERT_EQ(::stat(("/dev/shm" + name).c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0400u);
  // a stack that makes it writable again and truncates it
  ASSERT_EQ(::chmod(("/dev/shm" + name).c_str(), 0600), 0);
  ASSERT_EQ(::truncate(("/dev/shm" + name).c_str(), 0), 0);
  EXPECT_NE(ErrorOf([&] { ring.Check(); }).find("the frame ring " + name + " shrank to 0 bytes"),
            std::string::npos);
  // a write past the file's end: without the guard, SIGBUS
  ring.Slot(1)->setTo(cv::Scalar(4, 5, 6));
  EXPECT_EQ(ring.Slot(1)->at<cv::Vec3b>(0, 0), cv::Vec3b(4, 5, 6));
  EXPECT_NE(ErrorOf([&] { ring.Check(); }).find("was cut short while hpa wrote"),
            std::string::npos);
}

// A SIGBUS outside every ring is still fatal (the guard does not swallow real faults).
#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define HPA_TEST_UNDER_ASAN 1
#endif
#endif

TEST(FrameRingTest, AFaultOutsideTheRingsStillKills) {
  const std::string name = "/hpa-flight-test-other-" + std::to_string(::getpid());
  FrameRing ring(name, 1, 8, 8);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // a mapping of a file cut short, not a ring
    char path[] = "/tmp/hpa-sigbus-XXXXXX";
    const int fd = ::mkstemp(path);
    ::unlink(path);
    if (fd < 0 || ::ftruncate(fd, 4096) != 0) ::_exit(2);
    auto* p = static_cast<volatile char*>(
        ::mmap(nullptr, 4096, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0));
    if (::ftruncate(fd, 0) != 0) ::_exit(2);
    p[0] = 1;
    ::_exit(0);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
#if defined(__SANITIZE_ADDRESS__) || defined(HPA_TEST_UNDER_ASAN)
  // AddressSanitizer takes SIGBUS itself: it reports the fault and exits non-zero
  EXPECT_TRUE(WIFSIGNALED(status) || (WIFEXITED(status) && WEXITSTATUS(status) != 0)) << status;
#else
  ASSERT_TRUE(WIFSIGNALED(status)) << status;
  EXPECT_EQ(WTERMSIG(status), SIGBUS);
#endif
}

// The stack's shell dies with the thread that started it (PR_SET_PDEATHSIG), and a process that
// left its group (a session of its own) is found by the socket in its environment.
TEST(FlightProcessTest, StacksDieWithHpaAndAreFoundByTheirSocket) {
  const std::string socket = "/tmp/hpa-flight-test-" + std::to_string(::getpid()) + "/x.sock";
  pid_t stack = 0;
  // started from a thread that then ends: as when hpa dies
  std::thread([&] {
    stack = SpawnFlightStack("exec sleep 30", socket, "/usr/bin:/bin");
    EXPECT_TRUE(Runs(stack, "sleep"));
  }).join();
  EXPECT_TRUE(Ended(stack));

  char pids[] = "/tmp/hpa-flight-pids-XXXXXX";
  const int fd = ::mkstemp(pids);
  ASSERT_GE(fd, 0);
  ::close(fd);
  const pid_t shell =
      SpawnFlightStack(std::string("setsid sleep 30 & echo $! > ") + pids + "; exec sleep 30",
                       socket, "/usr/bin:/bin");
  pid_t grandchild = 0;
  for (int i = 0; i < 200 && grandchild == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    FILE* f = std::fopen(pids, "r");
    if (f != nullptr) {
      if (std::fscanf(f, "%d", &grandchild) != 1) grandchild = 0;
      std::fclose(f);
    }
  }
  ::unlink(pids);
  ASSERT_GT(grandchild, 0);
  // $! is written as soon as the shell forks: wait until setsid has made the session, or the
  // group kill below would still reach it (and leave a zombie that kill(pid, 0) reports alive)
  for (int i = 0; i < 400 && ::getsid(grandchild) != grandchild; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_EQ(::getsid(grandchild), grandchild) << "setsid did not make a session";
  ::kill(-shell, SIGKILL);  // the group: the grandchild is not in it
  EXPECT_TRUE(Ended(shell));
  EXPECT_EQ(::kill(grandchild, 0), 0) << "the grandchild left the group and lives";
  EXPECT_EQ(KillProcessesOfSocket(socket), 1);
  bool gone = false;
  for (int i = 0; i < 400 && !gone; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    gone = ::kill(grandchild, 0) != 0;  // reaped by init once killed
  }
  EXPECT_TRUE(gone);
}

// A folder and a ring whose owner no longer runs are removed, with the process still carrying
// the folder's socket; a live owner's (this process's) are left alone.
TEST(FlightProcessTest, WhatADeadOwnerLeftIsReclaimed) {
  // an owner that has ended: a child, reaped
  const pid_t dead = ::fork();
  ASSERT_GE(dead, 0);
  if (dead == 0) ::_exit(0);
  ASSERT_EQ(::waitpid(dead, nullptr, 0), dead);
  const std::string dead_owner = std::to_string(dead) + "-1";
  const std::string live_owner = FlightOwnerTag();
  ASSERT_EQ(live_owner.rfind(std::to_string(::getpid()) + "-", 0), 0u) << live_owner;

  std::string stale_dir = "/tmp/hpa-flight-" + dead_owner + "-XXXXXX";
  ASSERT_NE(::mkdtemp(stale_dir.data()), nullptr);
  std::string live_dir = "/tmp/hpa-flight-" + live_owner + "-XXXXXX";
  ASSERT_NE(::mkdtemp(live_dir.data()), nullptr);
  const std::string stale_ring = "/hpa-flight-" + dead_owner + "-0";
  const std::string live_ring = "/hpa-flight-" + live_owner + "-test";
  for (const std::string& ring : {stale_ring, live_ring}) {
    const int fd = ::shm_open(ring.c_str(), O_CREAT | O_RDWR, 0600);
    ASSERT_GE(fd, 0);
    ::close(fd);
  }
  // a stack process left by the dead owner, carrying its socket
  const pid_t lingering = SpawnFlightStack("exec sleep 30", stale_dir + "/lockstep.sock", "/bin");
  ASSERT_TRUE(Runs(lingering, "sleep"));

  RemoveStaleFlightRuns();
  EXPECT_TRUE(Ended(lingering));
  EXPECT_FALSE(Exists(stale_dir));
  EXPECT_FALSE(Exists("/dev/shm" + stale_ring));
  EXPECT_TRUE(Exists(live_dir));
  EXPECT_TRUE(Exists("/dev/shm" + live_ring));
  ::rmdir(live_dir.c_str());
  ::shm_unlink(live_ring.c_str());
}

}  // namespace
}  // namespace hpa::runner
