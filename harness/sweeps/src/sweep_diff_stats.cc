// The paired tests of `hpa sweep-diff`: exact McNemar for rates, Wilcoxon signed-rank for
// continuous metrics, and their exact intervals (Hodges-Lehmann, Clopper-Pearson).

#include <algorithm>
#include <cmath>
#include <numeric>

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

namespace {

// P(W+ <= k) for k = 0 .. n(n+1)/2 under the signed-rank null with ranks 1..n (no ties).
std::vector<double> SignedRankCdf(int n) {
  const int max_sum = n * (n + 1) / 2;
  std::vector<double> count(max_sum + 1, 0.0);
  count[0] = 1.0;
  for (int r = 1; r <= n; ++r) {
    for (int s = max_sum; s >= r; --s) count[s] += count[s - r];
  }
  const double all = std::pow(2.0, n);
  double acc = 0.0;
  for (double& c : count) {
    acc += c / all;
    c = acc;
  }
  return count;
}

// Inverse of the regularised incomplete beta by bisection (Clopper-Pearson's bounds).
double BetaQuantile(double q, double a, double b) {
  // I_x(a, b) by the continued fraction (Numerical Recipes' betacf), x in (0, 1)
  const auto incomplete = [](double x, double a, double b) {
    if (x <= 0.0) return 0.0;
    if (x >= 1.0) return 1.0;
    const double front = std::exp(std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) +
                                  a * std::log(x) + b * std::log1p(-x));
    const bool flip = x > (a + 1.0) / (a + b + 2.0);
    const double aa = flip ? b : a, bb = flip ? a : b, xx = flip ? 1.0 - x : x;
    double c = 1.0, d = 1.0 - (aa + bb) * xx / (aa + 1.0);
    d = 1.0 / (std::fabs(d) < 1e-300 ? 1e-300 : d);
    double h = d;
    for (int m = 1; m <= 300; ++m) {
      for (int half = 0; half < 2; ++half) {
        const double num = half == 0
                               ? m * (bb - m) * xx / ((aa + 2 * m - 1) * (aa + 2 * m))
                               : -(aa + m) * (aa + bb + m) * xx / ((aa + 2 * m) * (aa + 2 * m + 1));
        d = 1.0 + num * d;
        d = 1.0 / (std::fabs(d) < 1e-300 ? 1e-300 : d);
        c = 1.0 + num / c;
        if (std::fabs(c) < 1e-300) c = 1e-300;
        h *= d * c;
      }
    }
    const double value = front * h / aa;
    return flip ? 1.0 - value : value;
  };
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (incomplete(mid, a, b) < q ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

ShiftEstimate HodgesLehmann(const std::vector<double>& differences) {
  std::vector<double> d;
  for (double x : differences) {
    if (std::isfinite(x)) d.push_back(x);
  }
  ShiftEstimate out;
  const int n = static_cast<int>(d.size());
  if (n == 0) return out;
  std::vector<double> walsh;
  walsh.reserve(static_cast<size_t>(n) * (n + 1) / 2);
  for (int i = 0; i < n; ++i) {
    for (int j = i; j < n; ++j) walsh.push_back(0.5 * (d[i] + d[j]));
  }
  std::sort(walsh.begin(), walsh.end());
  const size_t count = walsh.size();
  out.estimate =
      count % 2 == 1 ? walsh[count / 2] : 0.5 * (walsh[count / 2 - 1] + walsh[count / 2]);
  // k: the largest count with P(W+ <= k) <= 0.025; none (too few pairs): the whole range
  long k = -1;
  if (n <= 50) {
    const std::vector<double> cdf = SignedRankCdf(n);
    while (k + 1 < static_cast<long>(cdf.size()) && cdf[k + 1] <= 0.025) ++k;
  } else {
    const double mean = n * (n + 1) / 4.0;
    const double sd = std::sqrt(n * (n + 1.0) * (2.0 * n + 1.0) / 24.0);
    k = static_cast<long>(std::floor(mean - 1.959963984540054 * sd - 0.5));
  }
  if (k < 0) {
    out.ci95 = {walsh.front(), walsh.back()};
  } else {
    const size_t lo = std::min(static_cast<size_t>(k), count - 1);
    out.ci95 = {walsh[lo], walsh[count - 1 - lo]};
  }
  return out;
}

ShiftEstimate PairedRateDifference(int a_only, int b_only, int n) {
  ShiftEstimate out;
  if (n <= 0) return out;
  const int m = a_only + b_only;
  out.estimate = static_cast<double>(b_only - a_only) / n;
  if (m == 0) {
    // no discordant pair: the share favouring B is unknown, the discordant fraction's exact
    // upper bound (1 - 0.025^(1/n)) bounds |B - A|
    const double upper = 1.0 - std::pow(0.025, 1.0 / n);
    out.ci95 = {-upper, upper};
    return out;
  }
  const double p_lo = b_only == 0 ? 0.0 : BetaQuantile(0.025, b_only, m - b_only + 1);
  const double p_hi = b_only == m ? 1.0 : BetaQuantile(0.975, b_only + 1, m - b_only);
  const double scale = static_cast<double>(m) / n;
  out.ci95 = {scale * (2.0 * p_lo - 1.0), scale * (2.0 * p_hi - 1.0)};
  return out;
}

}  // namespace hpa
