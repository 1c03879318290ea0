#pragma once
// Status every filter step returns (STYLE.md: every solve and filter step returns a status).

namespace hpa {

/// What happened in one predict or update step of a filter.
enum class FilterStatus {
  kOk,          // step applied
  kNonFinite,   // input had NaN/Inf: ignored, state unchanged
  kTooOld,      // measurement older than the kept history: ignored
  kOutOfOrder,  // sample not after the previous one: ignored
  kRejected,    // measurement failed the innovation gate: ignored
};

/// Name of a status for logs.
inline const char* ToString(FilterStatus status) {
  switch (status) {
    case FilterStatus::kOk:
      return "ok";
    case FilterStatus::kNonFinite:
      return "non_finite";
    case FilterStatus::kTooOld:
      return "too_old";
    case FilterStatus::kOutOfOrder:
      return "out_of_order";
    case FilterStatus::kRejected:
      return "rejected";
  }
  return "unknown";
}

}  // namespace hpa
