#include "hpa/sim/camera_image_model.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <random>
#include <tuple>

#include "hpa/models/camera_model.h"

namespace hpa::sim {
namespace {

constexpr size_t kNoiseTableSize = size_t{1} << 22;  // > one frame's 2.76 M channel samples

// SplitMix64: a well-mixed 64-bit hash of (seed, frame) for the noise table offset.
uint64_t Mix(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// N(0, 1) samples shared by every model in the process (fixed seed: deterministic).
const std::vector<float>& UnitNormalTable() {
  static const std::vector<float> table = [] {
    std::vector<float> t(kNoiseTableSize);
    std::mt19937_64 rng(0x5eed);
    std::normal_distribution<float> normal(0.0f, 1.0f);
    for (float& v : t) v = normal(rng);
    return t;
  }();
  return table;
}

// Undistorted normalised coordinates of distorted ones, warm-started Newton with the analytic
// Jacobian of the radial-tangential model (a full-frame map is ~1 M solves).
Eigen::Vector2d UndistortWarm(const Eigen::Vector4d& k, const Eigen::Vector2d& x_d,
                              Eigen::Vector2d x) {
  for (int i = 0; i < 20; ++i) {
    const double u = x.x(), v = x.y(), r2 = u * u + v * v;
    const double radial = 1.0 + k[0] * r2 + k[1] * r2 * r2;
    const double dradial = 2.0 * k[0] + 4.0 * k[1] * r2;  // d radial / d(r2) * 2
    const Eigen::Vector2d f(u * radial + 2.0 * k[2] * u * v + k[3] * (r2 + 2.0 * u * u) - x_d.x(),
                            v * radial + k[2] * (r2 + 2.0 * v * v) + 2.0 * k[3] * u * v - x_d.y());
    if (f.squaredNorm() < 1e-26) break;
    Eigen::Matrix2d J;
    J(0, 0) = radial + u * dradial * u + 2.0 * k[2] * v + k[3] * 6.0 * u;
    J(0, 1) = u * dradial * v + 2.0 * k[2] * u + k[3] * 2.0 * v;
    J(1, 0) = v * dradial * u + k[2] * 2.0 * u + 2.0 * k[3] * v;
    J(1, 1) = radial + v * dradial * v + k[2] * 6.0 * v + 2.0 * k[3] * u;
    x -= J.inverse() * f;
  }
  return x;
}

struct Maps {
  double render_focal_px;
  cv::Mat map1, map2;
};

// Render focal length and the sensor -> render remap for one camera; cached per calibration.
const Maps& MapsFor(const Params& params) {
  static std::mutex mutex;
  static std::map<std::tuple<int, int, double, double, double, double, double>, Maps> cache;
  const Eigen::Vector4d& k = params.camera_distortion;
  const auto key = std::make_tuple(params.camera_width_px, params.camera_height_px,
                                   params.CameraFocalPx(), k[0], k[1], k[2], k[3]);
  std::lock_guard<std::mutex> lock(mutex);
  if (auto it = cache.find(key); it != cache.end()) return it->second;

  const int w = params.camera_width_px, h = params.camera_height_px;
  const double f_px = params.CameraFocalPx();
  const double cx = 0.5 * w, cy = 0.5 * h;
  // undistorted rays of every sensor pixel centre
  cv::Mat undistorted(h, w, CV_32FC2);
  double need_x = 0.0, need_y = 0.0;  // largest |x_n|, |y_n| the render must cover
  for (int row = 0; row < h; ++row) {
    Eigen::Vector2d guess((0.5 - cx) / f_px, (row + 0.5 - cy) / f_px);
    for (int col = 0; col < w; ++col) {
      const Eigen::Vector2d x_d((col + 0.5 - cx) / f_px, (row + 0.5 - cy) / f_px);
      const Eigen::Vector2d x_u = UndistortWarm(k, x_d, col == 0 ? x_d : guess);
      guess = x_u;
      undistorted.at<cv::Vec2f>(row, col) =
          cv::Vec2f(static_cast<float>(x_u.x()), static_cast<float>(x_u.y()));
      need_x = std::max(need_x, std::abs(x_u.x()));
      need_y = std::max(need_y, std::abs(x_u.y()));
    }
  }
  // the render spans |x_n| <= cx / f_r (half a pixel kept for bilinear interpolation)
  const double render_f_px =
      std::min({f_px, (cx - 1.0) / std::max(need_x, 1e-9), (cy - 1.0) / std::max(need_y, 1e-9)});
  cv::Mat map_x(h, w, CV_32FC1), map_y(h, w, CV_32FC1);
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const cv::Vec2f x_u = undistorted.at<cv::Vec2f>(row, col);
      // render pixel index coordinates (pixel i centred at i)
      map_x.at<float>(row, col) = static_cast<float>(cx + render_f_px * x_u[0] - 0.5);
      map_y.at<float>(row, col) = static_cast<float>(cy + render_f_px * x_u[1] - 0.5);
    }
  }
  Maps maps;
  maps.render_focal_px = render_f_px;
  cv::convertMaps(map_x, map_y, maps.map1, maps.map2, CV_16SC2);
  return cache.emplace(key, std::move(maps)).first->second;
}

}  // namespace

CameraImageModel::CameraImageModel(const Params& params, const CameraImageProfile& profile,
                                   uint64_t seed)
    : params_(params),
      profile_(profile),
      seed_(seed),
      render_focal_px_(params.CameraFocalPx()),
      distorted_(!params.camera_distortion.isZero()) {
  if (distorted_) {
    const Maps& maps = MapsFor(params);
    render_focal_px_ = maps.render_focal_px;
    map1_ = maps.map1;  // shared, read-only
    map2_ = maps.map2;
  }
  if (profile_.noise) {
    // DN per electron at this gain; variance in DN^2 = g * level + (g * read noise)^2
    const double g = 255.0 * profile_.analog_gain / profile_.full_well_e;
    noise_sd_dn_.resize(256);
    for (int level = 0; level < 256; ++level) {
      noise_sd_dn_[level] = static_cast<float>(
          std::sqrt(g * level + g * g * profile_.read_noise_e * profile_.read_noise_e));
    }
    unit_normal_ = UnitNormalTable();
  }
}

double CameraImageModel::render_fovy_deg() const {
  return 2.0 * std::atan(0.5 * params_.camera_height_px / render_focal_px_) * 180.0 / M_PI;
}

void CameraImageModel::Remap(const cv::Mat& pinhole, cv::Mat* out) {
  if (!distorted_) {
    pinhole.copyTo(*out);
    return;
  }
  cv::remap(pinhole, *out, map1_, map2_, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
}

void CameraImageModel::AddNoise(uint64_t frame_index, cv::Mat* image) const {
  if (!profile_.noise) return;
  const size_t mask = kNoiseTableSize - 1;
  const size_t offset = Mix(seed_ ^ Mix(frame_index)) & mask;
  const float* table = unit_normal_.data();
  const float* sd = noise_sd_dn_.data();
  const size_t row_values = static_cast<size_t>(image->cols) * image->channels();
  for (int row = 0; row < image->rows; ++row) {
    uint8_t* p = image->ptr<uint8_t>(row);
    size_t index = offset + static_cast<size_t>(row) * row_values;
    for (size_t i = 0; i < row_values; ++i, ++index) {
      p[i] = cv::saturate_cast<uint8_t>(p[i] + sd[p[i]] * table[index & mask]);
    }
  }
}

void CameraImageModel::ApplyOptics(const cv::Mat& pinhole, uint64_t frame_index, cv::Mat* sensor) {
  Remap(pinhole, &remapped_);
  if (profile_.psf_sigma_px > 0.0) {
    cv::GaussianBlur(remapped_, *sensor, cv::Size(0, 0), profile_.psf_sigma_px, 0.0,
                     cv::BORDER_REPLICATE);
  } else {
    remapped_.copyTo(*sensor);
  }
  AddNoise(frame_index, sensor);
}

void CameraImageModel::Apply(const cv::Mat& pinhole, const Eigen::Vector2d& blur_px,
                             const cv::Rect& blur_region, uint64_t frame_index, cv::Mat* sensor) {
  const double length_px = blur_px.norm();
  if (profile_.exposure_s <= 0.0 || !(length_px >= 0.5)) {
    ApplyOptics(pinhole, frame_index, sensor);
    return;
  }
  // fast motion blur: the region (grown by the smear) is convolved with a line kernel along
  // the image motion, centred on the mid-exposure position
  const int radius = static_cast<int>(std::ceil(0.5 * length_px)) + 1;
  cv::Mat kernel = cv::Mat::zeros(2 * radius + 1, 2 * radius + 1, CV_32F);
  const int samples = std::max(8, static_cast<int>(std::ceil(4.0 * length_px)));
  for (int i = 0; i < samples; ++i) {
    const double s = (i + 0.5) / samples - 0.5;
    const double x = radius + s * blur_px.x(), y = radius + s * blur_px.y();
    const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
    const float fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
    kernel.at<float>(y0, x0) += (1 - fx) * (1 - fy);
    kernel.at<float>(y0, x0 + 1) += fx * (1 - fy);
    kernel.at<float>(y0 + 1, x0) += (1 - fx) * fy;
    kernel.at<float>(y0 + 1, x0 + 1) += fx * fy;
  }
  kernel /= cv::sum(kernel)[0];
  const cv::Rect frame(0, 0, pinhole.cols, pinhole.rows);
  cv::Rect region = blur_region.area() > 0 ? blur_region : frame;
  region = cv::Rect(region.x - 2 * radius, region.y - 2 * radius, region.width + 4 * radius,
                    region.height + 4 * radius) &
           frame;
  pinhole.copyTo(blurred_);
  if (region.area() > 0) {
    cv::filter2D(pinhole(region), blurred_(region), -1, kernel, cv::Point(-1, -1), 0.0,
                 cv::BORDER_REPLICATE);
  }
  ApplyOptics(blurred_, frame_index, sensor);
}

}  // namespace hpa::sim
