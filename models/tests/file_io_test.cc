// The one input reader and the one atomic writer: an input must be a regular file of bounded
// size, and an output appears whole or not at all (the previous file survives a full disk).

#include "hpa/models/file_io.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "hpa/models/input_error.h"

namespace hpa {
namespace {

// A fresh scratch folder under /tmp.
std::string ScratchDir() {
  char name[] = "/tmp/hpa_file_io_XXXXXX";
  const char* dir = mkdtemp(name);
  EXPECT_NE(dir, nullptr);
  return dir;
}

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(FileIoTest, PartialPathKeepsTheExtension) {
  EXPECT_EQ(PartialPath("out/replay.mp4"), "out/replay.partial.mp4");
  EXPECT_EQ(PartialPath("out/golden.json"), "out/golden.partial.json");
  EXPECT_EQ(PartialPath("out.d/lock"), "out.d/lock.partial");
  EXPECT_EQ(PartialPath("out/.hidden"), "out/.hidden.partial");
}

TEST(FileIoTest, WritesWholeAndLeavesNoPartial) {
  const std::string dir = ScratchDir();
  WriteFileAtomic(dir + "/a.json", "{\"x\": 1}\n");
  EXPECT_EQ(Slurp(dir + "/a.json"), "{\"x\": 1}\n");
  struct stat st;
  EXPECT_NE(stat((dir + "/a.partial.json").c_str(), &st), 0);
}

// A full disk (here: the file-size limit, which fails a write as ENOSPC would) leaves the
// previous file whole and no partial file; the error names the file.
TEST(FileIoTest, AFullDiskLeavesThePreviousFileWhole) {
  const std::string dir = ScratchDir();
  const std::string path = dir + "/golden.json";
  WriteFileAtomic(path, "old\n");
  rlimit old_limit;
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
  rlimit small = old_limit;
  small.rlim_cur = 4096;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  std::string message;
  try {
    WriteFileAtomic(path, std::string(100000, 'x'));
  } catch (const OutputError& e) {
    message = e.what();
  }
  setrlimit(RLIMIT_FSIZE, &old_limit);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_EQ(Slurp(path), "old\n");
  struct stat st;
  EXPECT_NE(stat((dir + "/golden.partial.json").c_str(), &st), 0);
}

TEST(FileIoTest, ReadsOnlyRegularFilesOfBoundedSize) {
  const std::string dir = ScratchDir();
  WriteFileAtomic(dir + "/ok.csv", "t,x\n0,1\n");
  EXPECT_EQ(ReadInputFile(dir + "/ok.csv", "a CSV"), "t,x\n0,1\n");
  const auto message = [](const std::string& path, std::uintmax_t limit) {
    try {
      ReadInputFile(path, "a CSV", limit);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  ASSERT_EQ(mkfifo((dir + "/fifo").c_str(), 0600), 0);
  EXPECT_NE(message(dir + "/fifo", 1 << 20).find("not a regular file"), std::string::npos);
  EXPECT_NE(message(dir, 1 << 20).find("not a regular file"), std::string::npos);
  EXPECT_NE(message("/dev/zero", 1 << 20).find("not a regular file"), std::string::npos);
  EXPECT_NE(message(dir + "/ok.csv", 4).find("larger than 4 bytes"), std::string::npos);
  EXPECT_NE(message(dir + "/missing", 1 << 20).find("cannot read a CSV"), std::string::npos);
  EXPECT_NE(message("", 1 << 20).find("an empty path"), std::string::npos);
}

}  // namespace
}  // namespace hpa
