#include "hpa/models/file_io.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "hpa/models/input_error.h"

namespace hpa {

void CheckInputFile(const std::string& path, const std::string& what, std::uintmax_t max_bytes) {
  if (path.empty()) throw InputError("", "", "an empty path given for " + what);
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) throw InputError(path, "", "cannot read " + what);
  if (!std::filesystem::is_regular_file(status)) {
    throw InputError(path, "", "not a regular file (a FIFO, device or folder?): expected " + what);
  }
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec || size > max_bytes) {
    const std::string limit = max_bytes >= (1u << 20) ? std::to_string(max_bytes >> 20) + " MiB"
                                                      : std::to_string(max_bytes) + " bytes";
    throw InputError(path, "", "larger than " + limit + ": not " + what);
  }
}

std::string ReadInputFile(const std::string& path, const std::string& what,
                          std::uintmax_t max_bytes) {
  CheckInputFile(path, what, max_bytes);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "cannot read " + what);
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path, "", "cannot read " + what);
  // the size was checked before the open; a file that grew since is still bounded here
  if (text.str().size() > max_bytes) {
    throw InputError(path, "", "grew past its size limit while read: not " + what);
  }
  return text.str();
}

std::string PartialPath(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  const bool has_ext = dot != std::string::npos && (slash == std::string::npos || dot > slash + 1);
  return has_ext ? path.substr(0, dot) + ".partial" + path.substr(dot) : path + ".partial";
}

std::string WriteErrorText(int errnum) {
  if (errnum == 0) return "write failed (disk full?)";
  const std::string text = std::strerror(errnum);
  if (errnum == EFBIG) return text + ": the file-size limit (ulimit -f) is reached";
  if (errnum == ENOSPC || errnum == EDQUOT) return text + ": the disk (or quota) is full";
  return text;
}

void CommitPartial(const std::string& path) {
  const std::string partial = PartialPath(path);
  const int fd = open(partial.c_str(), O_RDONLY);
  const bool synced = fd >= 0 && fsync(fd) == 0;
  const int sync_errno = errno;
  if (fd >= 0) close(fd);
  if (!synced) {
    std::remove(partial.c_str());
    throw OutputError(path, WriteErrorText(sync_errno));
  }
  if (std::rename(partial.c_str(), path.c_str()) != 0) {
    const int rename_errno = errno;
    std::remove(partial.c_str());
    throw OutputError(path, std::strerror(rename_errno));
  }
}

void WriteFileAtomic(const std::string& path, const std::string& text) {
  const std::string partial = PartialPath(path);
  {
    std::ofstream out(partial, std::ios::binary | std::ios::trunc);
    if (!out) throw OutputError(path, std::strerror(errno));
    errno = 0;
    out << text;
    out.flush();
    if (!out) {
      const int write_errno = errno;
      out.close();
      std::remove(partial.c_str());
      throw OutputError(path, WriteErrorText(write_errno));
    }
  }
  CommitPartial(path);
}

}  // namespace hpa
