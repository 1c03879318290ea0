#pragma once
// A temporary folder private to one test in one process: ctest runs every test case as its own
// process, in parallel, so fixed names under testing::TempDir() race (seen: one case read
// another's half-written sweep file).

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <string>

namespace hpa {

/// TempDir()/hpa_<pid>_<suite>_<test>/, created on first use; returns it with a trailing '/'.
inline std::string TestTempDir() {
  const auto* info = testing::UnitTest::GetInstance()->current_test_info();
  std::string name = "hpa_" + std::to_string(getpid());
  if (info != nullptr) name += std::string("_") + info->test_suite_name() + "_" + info->name();
  for (char& c : name) {
    if (c == '/') c = '_';  // parameterised test names hold '/'
  }
  const std::string dir = testing::TempDir() + "/" + name;
  mkdir(dir.c_str(), 0755);
  return dir + "/";
}

}  // namespace hpa
