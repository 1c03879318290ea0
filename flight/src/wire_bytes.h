#pragma once
// A message body's bytes as the table's base types: Writer appends little-endian numbers and
// texts, Reader reads them back with every read bounds-checked, and the checks a number or a
// flags value read passes against its field's declaration (message_table.cc defines them).

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "wire_table.h"

namespace hpa::flight::wire {

/// Appends little-endian numbers (this machine's order: x86-64 and arm64 are little-endian).
class Writer {
 public:
  /// Appends one f64.
  void F64(double v) { Raw(&v, 8); }
  /// Appends one u32.
  void U32(uint32_t v) { Raw(&v, 4); }
  /// Appends a u32 byte count and the bytes.
  void Text(const std::string& s);
  std::vector<uint8_t> bytes;  // what was written

 private:
  void Raw(const void* p, size_t n);
};

/// Reads what Writer wrote; every read is bounds-checked, every refusal names the message.
class Reader {
 public:
  /// Reads `bytes`, a body of the message `message` ("tick", "finish", "tick_reply").
  Reader(const std::vector<uint8_t>& bytes, std::string message)
      : bytes_(bytes), message_(std::move(message)) {}
  /// Reads one f64.
  double F64();
  /// Reads one u32.
  uint32_t U32();
  /// Reads a text field: its byte count, then UTF-8; refused when longer than the message or
  /// not UTF-8.
  std::string Text(const Field& f, const std::string& at);
  /// Reads a list's count; refused when the message cannot hold that many items.
  uint32_t Count(const Field& f);
  /// Refuses bytes after the message's end.
  void End();
  /// Throws ProtocolError "malformed MESSAGE message: WHAT".
  [[noreturn]] void Fail(const std::string& what) const;

 private:
  void Raw(void* p, size_t n);
  const std::vector<uint8_t>& bytes_;
  std::string message_;
  size_t pos_ = 0;
};

/// Refuses `v` (a number of field `f` at `at`) outside the field's declared checks.
void CheckNumber(const Reader& r, const Field& f, const std::string& at, double v);
/// Refuses a flags value with unknown bits or a bit without the bit it requires.
void CheckFlags(const Reader& r, const Field& f, const std::string& at, uint32_t flags);

}  // namespace hpa::flight::wire
