// The paired tests of `hpa sweep-diff`: exact McNemar for rates, Wilcoxon signed-rank for
// continuous metrics, and the bootstrap interval of the mean difference.

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "hpa/scenarios/sweep_diff.h"

namespace hpa {

double McNemarPValue(int a_only, int b_only) {
  const int n = a_only + b_only;
  if (n == 0) return 1.0;
  const int k = std::min(a_only, b_only);
  double tail = 0.0;  // P(X <= k), X ~ Binomial(n, 1/2), summed in logs
  for (int i = 0; i <= k; ++i) {
    tail += std::exp(std::lgamma(n + 1.0) - std::lgamma(i + 1.0) - std::lgamma(n - i + 1.0) -
                     n * std::log(2.0));
  }
  return std::min(1.0, 2.0 * tail);
}

double SignedRankPValue(const std::vector<double>& differences) {
  std::vector<double> d;
  for (double x : differences) {
    if (x != 0.0 && std::isfinite(x)) d.push_back(x);
  }
  const int n = static_cast<int>(d.size());
  if (n == 0) return 1.0;
  // mid-ranks of |d| (ties share their average rank)
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](int i, int j) { return std::fabs(d[i]) < std::fabs(d[j]); });
  std::vector<double> rank(n);
  double tie_term = 0.0;
  for (int i = 0; i < n;) {
    int j = i;
    while (j + 1 < n && std::fabs(d[order[j + 1]]) == std::fabs(d[order[i]])) ++j;
    const double mid = 0.5 * (i + j) + 1.0;
    for (int k = i; k <= j; ++k) rank[order[k]] = mid;
    const double t = j - i + 1;
    tie_term += t * t * t - t;
    i = j + 1;
  }
  double w_plus = 0.0;
  for (int i = 0; i < n; ++i) {
    if (d[i] > 0) w_plus += rank[i];
  }
  const double total = n * (n + 1) / 2.0;
  if (n <= 25) {
    // exact null distribution of W+ over doubled (integer) ranks: every sign equally likely
    const int max_sum = static_cast<int>(std::lround(2 * total));
    std::vector<double> count(max_sum + 1, 0.0);
    count[0] = 1.0;
    for (int i = 0; i < n; ++i) {
      const int r2 = static_cast<int>(std::lround(2 * rank[i]));
      for (int s = max_sum; s >= r2; --s) count[s] += count[s - r2];
    }
    const double all = std::pow(2.0, n);
    const int observed = static_cast<int>(std::lround(2 * w_plus));
    const int mirrored = max_sum - observed;
    const int low = std::min(observed, mirrored), high = std::max(observed, mirrored);
    double tails = 0.0;
    for (int s = 0; s <= max_sum; ++s) {
      if (s <= low || s >= high) tails += count[s];
    }
    return std::min(1.0, tails / all);
  }
  const double mean = total / 2.0;
  const double var = n * (n + 1.0) * (2.0 * n + 1.0) / 24.0 - tie_term / 48.0;
  const double z = (std::fabs(w_plus - mean) - 0.5) / std::sqrt(var);
  return std::min(1.0, std::erfc(std::max(0.0, z) / std::sqrt(2.0)));
}

std::pair<double, double> BootstrapMeanCi(const std::vector<double>& differences, int resamples) {
  const size_t n = differences.size();
  if (n == 0) return {0.0, 0.0};
  std::mt19937_64 rng(20261122);
  std::uniform_int_distribution<size_t> pick(0, n - 1);
  std::vector<double> means(resamples);
  for (int r = 0; r < resamples; ++r) {
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i) sum += differences[pick(rng)];
    means[r] = sum / n;
  }
  std::sort(means.begin(), means.end());
  const auto at = [&](double q) {
    return means[std::min<size_t>(means.size() - 1, static_cast<size_t>(q * (resamples - 1)))];
  };
  return {at(0.025), at(0.975)};
}

}  // namespace hpa
