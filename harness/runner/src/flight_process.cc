#include "harness/runner/src/flight_process.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <optional>
#include <set>
#include <stdexcept>
#include <vector>

extern char** environ;

namespace hpa::runner {
namespace {

constexpr char kSocketVariable[] = "HPA_FLIGHT_SOCKET=";
constexpr char kPrefix[] = "hpa-flight-";  // of socket folders in /tmp and rings in /dev/shm

// The whole of a small /proc file ("" when it cannot be read: the process has gone).
std::string ReadProcFile(const std::string& path) {
  std::string text;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return text;
  char buf[4096];
  ssize_t n;
  while ((n = ::read(fd, buf, sizeof buf)) > 0 || (n < 0 && errno == EINTR)) {
    if (n > 0) text.append(buf, static_cast<size_t>(n));
  }
  ::close(fd);
  return text;
}

// The start time of process `pid` in clock ticks since boot (/proc/PID/stat field 22), or
// nothing when it is not running (gone, or a zombie its parent has not reaped).
std::optional<unsigned long long> StartTicks(pid_t pid) {
  const std::string stat = ReadProcFile("/proc/" + std::to_string(pid) + "/stat");
  // after the command name in parentheses (which may hold spaces): field 3 (the state) onwards
  const size_t close = stat.rfind(')');
  if (close == std::string::npos || close + 2 >= stat.size()) return std::nullopt;
  const char state = stat[close + 2];
  if (state == 'Z' || state == 'X' || state == 'x') return std::nullopt;
  const char* p = stat.c_str() + close + 1;
  for (int field = 3; field < 22; ++field) {
    while (*p == ' ') ++p;
    while (*p != ' ' && *p != '\0') ++p;
  }
  char* end = nullptr;
  const unsigned long long ticks = std::strtoull(p, &end, 10);
  if (end == p) return std::nullopt;
  return ticks;
}

// The owner (pid, start ticks) a name "hpa-flight-PID-START-..." carries, if it is one.
std::optional<std::pair<pid_t, unsigned long long>> OwnerOf(const std::string& name) {
  if (name.compare(0, sizeof kPrefix - 1, kPrefix) != 0) return std::nullopt;
  const char* p = name.c_str() + sizeof kPrefix - 1;
  char* end = nullptr;
  const long pid = std::strtol(p, &end, 10);
  if (end == p || *end != '-' || pid <= 0) return std::nullopt;
  p = end + 1;
  const unsigned long long start = std::strtoull(p, &end, 10);
  if (end == p || *end != '-') return std::nullopt;
  return std::make_pair(static_cast<pid_t>(pid), start);
}

// Whether the owner a name carries is no longer running (a name that carries none: false).
bool OwnerGone(const std::string& name) {
  const auto owner = OwnerOf(name);
  if (!owner) return false;
  const std::optional<unsigned long long> start = StartTicks(owner->first);
  return !start || *start != owner->second;
}

// Sends SIGKILL to every process of this user but this one whose HPA_FLIGHT_SOCKET satisfies
// `matches`, each through a pidfd opened before its environment is read (a pid reused meanwhile
// is not hit); returns the pids signalled.
std::set<pid_t> KillMatching(const std::function<bool(const std::string&)>& matches) {
  std::set<pid_t> killed;
  DIR* proc = ::opendir("/proc");
  if (proc == nullptr) return killed;
  while (const dirent* entry = ::readdir(proc)) {
    char* end = nullptr;
    const long pid = std::strtol(entry->d_name, &end, 10);
    if (end == entry->d_name || *end != '\0' || pid <= 0 || pid == ::getpid()) continue;
    const std::string dir = std::string("/proc/") + entry->d_name;
    struct stat st {};
    if (::stat(dir.c_str(), &st) != 0 || st.st_uid != ::geteuid()) continue;
    const int pidfd = static_cast<int>(::syscall(SYS_pidfd_open, static_cast<pid_t>(pid), 0));
    const std::string env = ReadProcFile(dir + "/environ");
    bool hit = false;
    for (size_t at = 0; at < env.size();) {
      const size_t next = env.find('\0', at);
      const size_t len = (next == std::string::npos ? env.size() : next) - at;
      if (len >= sizeof kSocketVariable - 1 &&
          env.compare(at, sizeof kSocketVariable - 1, kSocketVariable) == 0) {
        hit =
            matches(env.substr(at + sizeof kSocketVariable - 1, len - sizeof kSocketVariable + 1));
        break;
      }
      at += len + 1;
    }
    if (hit) {
      if (pidfd >= 0) {
        ::syscall(SYS_pidfd_send_signal, pidfd, SIGKILL, nullptr, 0);
      } else {
        ::kill(static_cast<pid_t>(pid), SIGKILL);
      }
      killed.insert(static_cast<pid_t>(pid));
    }
    if (pidfd >= 0) ::close(pidfd);
  }
  ::closedir(proc);
  return killed;
}

// KillMatching until a pass finds no process it had not signalled yet (a process forked during
// a pass carries the same environment); returns how many were signalled.
int KillAllMatching(const std::function<bool(const std::string&)>& matches) {
  std::set<pid_t> all;
  for (int pass = 0; pass < 10; ++pass) {
    bool more = false;
    for (const pid_t pid : KillMatching(matches)) more = all.insert(pid).second || more;
    if (!more) break;
  }
  return static_cast<int>(all.size());
}

// The names in `folder` of this user's entries that start with kPrefix.
std::vector<std::string> OwnEntries(const std::string& folder) {
  std::vector<std::string> names;
  DIR* dir = ::opendir(folder.c_str());
  if (dir == nullptr) return names;
  while (const dirent* entry = ::readdir(dir)) {
    const std::string name = entry->d_name;
    struct stat st {};
    if (name.compare(0, sizeof kPrefix - 1, kPrefix) != 0 ||
        ::lstat((folder + "/" + name).c_str(), &st) != 0 || st.st_uid != ::geteuid()) {
      continue;
    }
    names.push_back(name);
  }
  ::closedir(dir);
  return names;
}

}  // namespace

std::string FlightOwnerTag() {
  const pid_t pid = ::getpid();
  return std::to_string(pid) + "-" + std::to_string(StartTicks(pid).value_or(0));
}

pid_t SpawnFlightStack(const std::string& command, const std::string& socket_path,
                       const std::string& path_env) {
  // everything the child needs is built before fork: after it, in a process with threads,
  // only async-signal-safe calls
  std::vector<std::string> env_text;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string entry = *e;
    if (entry.compare(0, sizeof kSocketVariable - 1, kSocketVariable) == 0 ||
        entry.compare(0, 5, "PATH=") == 0) {
      continue;
    }
    env_text.push_back(entry);
  }
  env_text.push_back(kSocketVariable + socket_path);
  env_text.push_back("PATH=" + path_env);
  std::vector<char*> envp;
  for (std::string& entry : env_text) envp.push_back(entry.data());
  envp.push_back(nullptr);
  const char* argv[] = {"sh", "-c", command.c_str(), nullptr};
  const pid_t parent = ::getpid();

  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  if (pid == 0) {
    ::setpgid(0, 0);  // its own process group: the whole command can be stopped
    // killed when hpa dies, however it dies (and at once if hpa is gone already)
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);
    sigset_t none;
    sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    ::dup2(2, 1);  // its output goes to stderr, never into hpa's stdout
    ::execve("/bin/sh", const_cast<char* const*>(argv), envp.data());
    ::_exit(127);
  }
  ::setpgid(pid, pid);
  return pid;
}

int KillProcessesOfSocket(const std::string& socket_path) {
  return KillAllMatching([&](const std::string& path) { return path == socket_path; });
}

void RemoveStaleFlightRuns() {
  // the processes of a dead owner's stack first: they may hold its folder and ring
  const std::string tmp_prefix = std::string("/tmp/") + kPrefix;
  KillAllMatching([&](const std::string& path) {
    if (path.compare(0, tmp_prefix.size(), tmp_prefix) != 0) return false;
    return OwnerGone(path.substr(5, path.find('/', 5) - 5));
  });
  for (const std::string& name : OwnEntries("/tmp")) {
    if (!OwnerGone(name)) continue;
    const std::string dir = "/tmp/" + name;
    ::unlink((dir + "/lockstep.sock").c_str());
    ::rmdir(dir.c_str());  // only what a run leaves there: a folder holding more stays
  }
  for (const std::string& name : OwnEntries("/dev/shm")) {
    if (OwnerGone(name)) ::shm_unlink(("/" + name).c_str());
  }
}

}  // namespace hpa::runner
