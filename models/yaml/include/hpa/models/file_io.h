#pragma once
// Every input file hpa reads whole, and every output file it writes, goes through here: an input
// must be a regular file of bounded size (a FIFO would block, /dev/zero never ends), and an
// output appears whole under its name or not at all (a full disk or a kill leaves the previous
// file, never a cut-off one that looks complete).

#include <cstdint>
#include <string>

namespace hpa {

/// Largest input file read whole (golden.json, runs.jsonl, a reference CSV, a log.csv): far
/// above any real one (a 100 000-run runs.jsonl is about 200 MiB), small enough that a runaway
/// file cannot exhaust memory.
constexpr std::uintmax_t kMaxInputFileBytes = std::uintmax_t{1} << 30;

/// Checks that `path` is a regular file of at most `max_bytes`; throws InputError naming the
/// file and `what` it should have been ("a reference CSV").
void CheckInputFile(const std::string& path, const std::string& what,
                    std::uintmax_t max_bytes = kMaxInputFileBytes);

/// The whole text of an input file, checked by CheckInputFile first.
std::string ReadInputFile(const std::string& path, const std::string& what,
                          std::uintmax_t max_bytes = kMaxInputFileBytes);

/// The temporary name an output is written under before WriteFileAtomic's rename: beside the
/// file (same file system) and ending in the file's own extension, so that writers that choose
/// a format by extension (a video, an image) can write it too. "out/replay.mp4" ->
/// "out/replay.partial.mp4".
std::string PartialPath(const std::string& path);

/// Why a write failed, for a message naming the file: strerror(errnum), saying for EFBIG that
/// the file-size limit (`ulimit -f`) was reached and for ENOSPC or EDQUOT that the disk or the
/// quota is full (hpa ignores SIGXFSZ, so a write past the limit fails with EFBIG, reported as a
/// full disk is). errnum 0 (a stream that set no errno): "write failed (disk full?)".
std::string WriteErrorText(int errnum);

/// Moves a finished PartialPath(path) onto path (fsync first): the one step that makes an output
/// visible. Throws OutputError naming `path`; the partial file is removed on failure.
void CommitPartial(const std::string& path);

/// Writes `text` to `path` atomically: PartialPath, checked and synced, then renamed onto
/// `path`. Throws OutputError naming `path` (a full disk, no permission, a folder in the way);
/// the previous file at `path` is then untouched.
void WriteFileAtomic(const std::string& path, const std::string& text);

}  // namespace hpa
