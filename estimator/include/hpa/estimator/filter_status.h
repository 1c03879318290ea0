#pragma once
// Status every filter step returns, the innovation gate every measurement update passes, and the
// running counts of both that the estimator publishes as its health.

#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace hpa {

/// What happened in one predict or update step of a filter.
enum class FilterStatus {
  kOk,          // step applied
  kNonFinite,   // input had NaN/Inf (or a singular innovation covariance): ignored, state unchanged
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

/// Chi-square innovation gate of a measurement update. A measurement whose normalised innovation
/// squared NIS = r^T S^-1 r exceeds nis_threshold is rejected, unless the previous
/// max_consecutive_rejections measurements were all rejected: a run of rejections means the
/// filter, not the sensor, is wrong, so the next measurement is accepted anyway (a forced accept).
struct InnovationGate {
  double nis_threshold = std::numeric_limits<double>::infinity();  // NIS bound (dimensionless)
  int max_consecutive_rejections = 0;  // rejections in a row before a forced accept
};

/// Running counts of what a filter's steps did (one per filter; read through the estimator's
/// health).
struct FilterCounts {
  int accepted_updates = 0;  // measurements fused, forced accepts included
  int rejected_updates = 0;  // measurements refused by the innovation gate
  int forced_accepts = 0;    // measurements fused although over the gate (the reset path)
  int non_finite = 0;        // steps refused for NaN/Inf input or a singular innovation covariance
  int too_old = 0;           // measurements older than the kept history
  int out_of_order = 0;      // samples not after the previous one
  double last_nis = 0.0;     // NIS of the latest measurement that reached the gate

  /// Counts a refused step (kOk and kRejected are counted by the update itself).
  void CountRefused(FilterStatus status) {
    if (status == FilterStatus::kNonFinite) ++non_finite;
    if (status == FilterStatus::kTooOld) ++too_old;
    if (status == FilterStatus::kOutOfOrder) ++out_of_order;
  }
  /// The counts as (prefix + name, value) pairs, in a fixed order.
  std::vector<std::pair<std::string, double>> Fields(const std::string& prefix) const {
    return {{prefix + "accepted_updates", accepted_updates},
            {prefix + "rejected_updates", rejected_updates},
            {prefix + "forced_accepts", forced_accepts},
            {prefix + "non_finite", non_finite},
            {prefix + "too_old", too_old},
            {prefix + "out_of_order", out_of_order},
            {prefix + "last_nis", last_nis}};
  }
};

}  // namespace hpa
