#include "hpa/sim/camera_image_model.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <future>
#include <map>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <random>
#include <system_error>
#include <thread>
#include <tuple>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "hpa/models/camera_model.h"
#include "hpa/models/seed_streams.h"

namespace hpa::sim {
namespace {

constexpr size_t kNoiseTableSize = size_t{1} << 22;  // > one frame's 2.76 M channel samples
constexpr uint64_t kNoiseTableSeed = 0x5eed;

// Narrowest band over which the fast motion blur fades into the unblurred image (px).
constexpr int kMinBlurFadePx = 16;

// Splits [0, n) into contiguous parts and runs body(begin, end) on each, one thread per part
// (the calling thread takes the first). Threads end before it returns, so a process may fork after.
template <typename Body>
void ParallelRanges(size_t n, const Body& body) {
  const size_t parts = std::clamp<size_t>(std::thread::hardware_concurrency(), 1, 4);
  std::vector<std::thread> threads;
  for (size_t p = 1; p < parts; ++p) {
    try {
      threads.emplace_back([&body, n, p, parts] { body(n * p / parts, n * (p + 1) / parts); });
    } catch (const std::system_error&) {
      body(n * p / parts, n * (p + 1) / parts);  // no thread to be had: this part here
    }
  }
  body(0, n / parts);
  for (std::thread& t : threads) t.join();
}

// std::generate_canonical<float, 24> of one mt19937_64 output, as libstdc++ computes it.
inline float CanonicalFloat(uint64_t bits) {
  const float r = static_cast<float>(bits) / 18446744073709551616.0f;  // / 2^64
  return r >= 1.0f ? std::nextafter(1.0f, 0.0f) : r;
}

// The values std::normal_distribution<float>(0, 1) draws from mt19937_64(seed), bit for bit
// (libstdc++'s Marsaglia polar method), computed in two passes: the sequential one draws the
// uniforms and keeps each accepted pair (x, y) in the table where its two values go; the
// logarithms and roots, most of the cost, run on every core and scale the pairs in place (r2 is
// recomputed there by the same float operations). The table test compares it with the standard
// library's own loop.
std::vector<float> PolarNormalTable(size_t size, uint64_t seed) {
  std::mt19937_64 rng(seed);
  const size_t pairs = (size + 1) / 2;
  std::vector<float> table(2 * pairs);
  for (size_t i = 0; i < pairs; ++i) {
    float x, y, r2;
    do {
      x = static_cast<float>(2.0f * CanonicalFloat(rng()) - 1.0);
      y = static_cast<float>(2.0f * CanonicalFloat(rng()) - 1.0);
      r2 = x * x + y * y;
    } while (r2 > 1.0 || r2 == 0.0);
    // the distribution returns y * mult first and keeps x * mult for the next draw
    table[2 * i] = y;
    table[2 * i + 1] = x;
  }
  ParallelRanges(pairs, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      const float y = table[2 * i], x = table[2 * i + 1];
      const float r2 = x * x + y * y;
      const float mult = std::sqrt(-2 * std::log(r2) / r2);
      table[2 * i] = y * mult;
      table[2 * i + 1] = x * mult;
    }
  });
  table.resize(size);
  return table;
}

struct Maps {
  double render_focal_px;
  cv::Mat map1, map2;    // fixed-point maps for cv::remap
  cv::Mat map_x, map_y;  // the same in float: which render pixels a sensor region reads
  MapOrder x_order = MapOrder::kNone, y_order = MapOrder::kNone;  // as checked on every value
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
  // undistorted rays of every sensor pixel centre, rows split across threads (each row is its
  // own chain of warm starts, so the split does not change a value)
  cv::Mat undistorted(h, w, CV_32FC2);
  std::vector<double> row_need_x(h), row_need_y(h);  // largest |x_n|, |y_n| of each row
  ParallelRanges(h, [&](size_t row_begin, size_t row_end) {
    for (int row = static_cast<int>(row_begin); row < static_cast<int>(row_end); ++row) {
      Eigen::Vector2d guess((0.5 - cx) / f_px, (row + 0.5 - cy) / f_px);
      for (int col = 0; col < w; ++col) {
        const Eigen::Vector2d x_d((col + 0.5 - cx) / f_px, (row + 0.5 - cy) / f_px);
        // warm start from the neighbour: a full-frame map is ~1 M solves
        const Eigen::Vector2d x_u = UndistortNormalised(k, x_d, col == 0 ? nullptr : &guess);
        guess = x_u;
        undistorted.at<cv::Vec2f>(row, col) =
            cv::Vec2f(static_cast<float>(x_u.x()), static_cast<float>(x_u.y()));
        row_need_x[row] = std::max(row_need_x[row], std::abs(x_u.x()));
        row_need_y[row] = std::max(row_need_y[row], std::abs(x_u.y()));
      }
    }
  });
  // the largest |x_n|, |y_n| the render must cover
  const double need_x = *std::max_element(row_need_x.begin(), row_need_x.end());
  const double need_y = *std::max_element(row_need_y.begin(), row_need_y.end());
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
  maps.map_x = map_x;
  maps.map_y = map_y;
  // a lens whose distortion keeps the pixel order lets a region's bounds be read off its edges
  maps.x_order = CheckedMapOrder(map_x, MapOrder::kIncreasingAlongRows);
  maps.y_order = CheckedMapOrder(map_y, MapOrder::kIncreasingDownColumns);
  return cache.emplace(key, std::move(maps)).first->second;
}

}  // namespace

MapOrder CheckedMapOrder(const cv::Mat& map, MapOrder order) {
  if (order == MapOrder::kNone) return order;
  // each value against its left neighbour (along rows) or the one above it (down columns)
  const bool along_rows = order == MapOrder::kIncreasingAlongRows;
  for (int row = along_rows ? 0 : 1; row < map.rows; ++row) {
    const float* v = map.ptr<float>(row);
    const float* before = along_rows ? v - 1 : map.ptr<float>(row - 1);
    for (int col = along_rows ? 1 : 0; col < map.cols; ++col) {
      if (!(v[col] >= before[col])) return MapOrder::kNone;
    }
  }
  return order;
}

void MapRange(const cv::Mat& map, const cv::Rect& area, MapOrder order, double* min, double* max) {
  if (order == MapOrder::kNone) {
    cv::minMaxLoc(map(area), min, max);
    return;
  }
  // the first and last column (x along rows) or row (y down columns) hold the extremes
  const bool along_rows = order == MapOrder::kIncreasingAlongRows;
  float lo = map.at<float>(area.y, area.x), hi = lo;
  const int n = along_rows ? area.height : area.width;
  for (int i = 0; i < n; ++i) {
    const float first =
        along_rows ? map.at<float>(area.y + i, area.x) : map.at<float>(area.y, area.x + i);
    const float last = along_rows ? map.at<float>(area.y + i, area.x + area.width - 1)
                                  : map.at<float>(area.y + area.height - 1, area.x + i);
    lo = std::min(lo, first);
    hi = std::max(hi, last);
  }
  *min = lo;
  *max = hi;
}

void AddLevelScaledNoise(uint8_t* values, const float* sd, const float* unit_normal, size_t n) {
  size_t i = 0;
#if defined(__SSE2__)
  // four values at a time, the same float operations as the scalar loop below: the sum rounded
  // by cvtps (nearest even, as cv::saturate_cast's cvRound), clamped by the saturating packs
  const __m128i zero = _mm_setzero_si128();
  for (; i + 4 <= n; i += 4) {
    int four;
    std::memcpy(&four, values + i, 4);
    const __m128i bytes_in = _mm_cvtsi32_si128(four);
    const __m128 value =
        _mm_cvtepi32_ps(_mm_unpacklo_epi16(_mm_unpacklo_epi8(bytes_in, zero), zero));
    const __m128 sd_of_value =
        _mm_setr_ps(sd[values[i]], sd[values[i + 1]], sd[values[i + 2]], sd[values[i + 3]]);
    const __m128 noisy = _mm_add_ps(value, _mm_mul_ps(sd_of_value, _mm_loadu_ps(unit_normal + i)));
    const __m128i rounded = _mm_cvtps_epi32(noisy);
    const __m128i bytes = _mm_packus_epi16(_mm_packs_epi32(rounded, rounded), zero);
    const int packed = _mm_cvtsi128_si32(bytes);
    std::memcpy(values + i, &packed, 4);
  }
#endif
  for (; i < n; ++i) {
    values[i] = cv::saturate_cast<uint8_t>(values[i] + sd[values[i]] * unit_normal[i]);
  }
}

CameraImageModel::CameraImageModel(const Params& params, const CameraImageProfile& profile,
                                   uint64_t seed)
    : params_(params),
      profile_(profile),
      seed_(seed),
      render_focal_px_(params.CameraFocalPx()),
      distorted_(!params.camera_distortion.isZero()) {
  // the noise table is first read when a frame's noise is added: it is computed beside the maps
  // and, on the first frame, beside the renderer's start (AddNoise waits for it)
  if (profile_.noise) noise_table_ = std::async(std::launch::async, [] { UnitNormalTable(); });
  if (distorted_) {
    const Maps& maps = MapsFor(params);
    render_focal_px_ = maps.render_focal_px;
    map1_ = maps.map1;  // shared, read-only
    map2_ = maps.map2;
    map_x_ = maps.map_x;
    map_y_ = maps.map_y;
    map_x_order_ = maps.x_order;
    map_y_order_ = maps.y_order;
  }
  if (profile_.noise) {
    // DN per electron at this gain; variance in DN^2 = g * level + (g * read noise)^2
    const double g = 255.0 * profile_.analog_gain / profile_.full_well_e;
    noise_sd_dn_.resize(256);
    for (int level = 0; level < 256; ++level) {
      noise_sd_dn_[level] = static_cast<float>(
          std::sqrt(g * level + g * g * profile_.read_noise_e * profile_.read_noise_e));
    }
  }
}

const std::vector<float>& CameraImageModel::UnitNormalTable() {
  static const std::vector<float> table = PolarNormalTable(kNoiseTableSize, kNoiseTableSeed);
  return table;
}

void CameraImageModel::PrepareSharedTables(const Params& params) {
  CameraImageProfile with_noise;
  with_noise.noise = true;
  PrepareTablesFor(params, with_noise);
}

void CameraImageModel::PrepareTablesFor(const Params& params, const CameraImageProfile& profile) {
  const bool distorted = !params.camera_distortion.isZero();
  if (!profile.noise || !distorted) {
    if (profile.noise) UnitNormalTable();
    if (distorted) MapsFor(params);
    return;
  }
  // both at once: the noise table's sequential pass beside the maps (the future waits for it,
  // also when the maps throw)
  const std::future<void> noise_table = std::async(std::launch::async, [] { UnitNormalTable(); });
  MapsFor(params);
}

double CameraImageModel::render_fovy_deg() const {
  return 2.0 * std::atan(0.5 * params_.camera_height_px / render_focal_px_) * 180.0 / M_PI;
}

int CameraImageModel::PsfRadiusPx() const {
  // OpenCV's Gaussian kernel for 8-bit images spans round(sigma * 6 + 1) | 1 pixels
  if (profile_.psf_sigma_px <= 0.0) return 0;
  return static_cast<int>(std::lround(profile_.psf_sigma_px * 6.0 + 1.0)) / 2 + 1;
}

int CameraImageModel::MotionBlurRadiusPx(const Eigen::Vector2d& blur_px) const {
  const double length_px = blur_px.norm();
  if (profile_.exposure_s <= 0.0 || !(length_px >= 0.5)) return 0;
  return static_cast<int>(std::ceil(0.5 * length_px)) + 1;
}

cv::Rect CameraImageModel::RenderRegion(const cv::Rect& sensor_region,
                                        const Eigen::Vector2d& blur_px) const {
  const cv::Rect frame(0, 0, params_.camera_width_px, params_.camera_height_px);
  if (sensor_region.area() == 0) return frame;
  const int psf = PsfRadiusPx();
  const cv::Rect grown = cv::Rect(sensor_region.x - psf, sensor_region.y - psf,
                                  sensor_region.width + 2 * psf, sensor_region.height + 2 * psf) &
                         frame;
  cv::Rect needed = grown;
  if (distorted_ && grown.area() > 0) {
    double min_x, max_x, min_y, max_y;
    MapRange(map_x_, grown, map_x_order_, &min_x, &max_x);
    MapRange(map_y_, grown, map_y_order_, &min_y, &max_y);
    // bilinear interpolation reads the pixel after the floor
    needed = cv::Rect(
        cv::Point(static_cast<int>(std::floor(min_x)) - 1, static_cast<int>(std::floor(min_y)) - 1),
        cv::Point(static_cast<int>(std::ceil(max_x)) + 2, static_cast<int>(std::ceil(max_y)) + 2));
  }
  // the motion-blur kernel reads this far around each pixel
  const int blur = MotionBlurRadiusPx(blur_px);
  needed =
      cv::Rect(needed.x - blur, needed.y - blur, needed.width + 2 * blur, needed.height + 2 * blur);
  return needed & frame;
}

void CameraImageModel::Remap(const cv::Mat& pinhole, const cv::Rect& area, cv::Mat* out) {
  out->create(pinhole.size(), pinhole.type());
  cv::Mat target = (*out)(area);
  if (!distorted_) {
    pinhole(area).copyTo(target);
    return;
  }
  cv::remap(pinhole, target, map1_(area), map2_(area), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
}

void CameraImageModel::AddNoise(uint64_t frame_index, const cv::Rect& area, cv::Mat* image) const {
  if (!profile_.noise) return;
  const size_t mask = kNoiseTableSize - 1;
  const size_t offset = SplitMix64(seed_ ^ SplitMix64(frame_index)) & mask;
  if (noise_table_.valid()) noise_table_.wait();
  const float* table = UnitNormalTable().data();  // shared, read-only
  // each value's noise is keyed by its place in the whole frame: a region gets the frame's noise
  const size_t channels = static_cast<size_t>(image->channels());
  const size_t row_values = static_cast<size_t>(image->cols) * channels;
  const size_t area_values = static_cast<size_t>(area.width) * channels;
  const auto row_start = [&](int row) {
    return (offset + static_cast<size_t>(row) * row_values + area.x * channels) & mask;
  };
  for (int row = area.y; row < area.y + area.height; ++row) {
    uint8_t* p = image->ptr<uint8_t>(row) + static_cast<size_t>(area.x) * channels;
    size_t start = row_start(row);
    // the table is far larger than the caches and each row reads a new stretch of it: the next
    // row's stretch is fetched while this one is worked on
    if (row + 1 < area.y + area.height) {
      const size_t next = row_start(row + 1);
      const size_t next_values = std::min(area_values, kNoiseTableSize - next);
      for (size_t i = 0; i < next_values; i += 64 / sizeof(float)) {
        __builtin_prefetch(table + next + i);
      }
    }
    // the row's table values are contiguous up to the table's end, then wrap to its start
    for (size_t done = 0; done < area_values;) {
      const size_t n = std::min(area_values - done, kNoiseTableSize - start);
      AddLevelScaledNoise(p + done, noise_sd_dn_.data(), table + start, n);
      done += n;
      start = 0;
    }
  }
}

void CameraImageModel::ApplyOptics(const cv::Mat& pinhole, uint64_t frame_index, cv::Mat* sensor,
                                   const cv::Rect& sensor_region) {
  const cv::Rect frame(0, 0, pinhole.cols, pinhole.rows);
  const cv::Rect area = sensor_region.area() > 0 ? (sensor_region & frame) : frame;
  sensor->create(pinhole.size(), pinhole.type());
  if (area.area() == 0) return;
  // the PSF reads this far around each pixel: those pixels are remapped too
  const int psf = PsfRadiusPx();
  const cv::Rect grown =
      cv::Rect(area.x - psf, area.y - psf, area.width + 2 * psf, area.height + 2 * psf) & frame;
  Remap(pinhole, grown, &remapped_);
  cv::Mat target = (*sensor)(area);
  if (profile_.psf_sigma_px > 0.0) {
    // on a sub-image OpenCV reads the neighbours from the parent (remapped above) and
    // replicates only at the frame's own edges: a region equals the whole frame's filtering
    cv::GaussianBlur(remapped_(area), target, cv::Size(0, 0), profile_.psf_sigma_px, 0.0,
                     cv::BORDER_REPLICATE);
  } else {
    remapped_(area).copyTo(target);
  }
  AddNoise(frame_index, area, sensor);
}

void CameraImageModel::Apply(const cv::Mat& pinhole, const Eigen::Vector2d& blur_px,
                             const cv::Rect& blur_region, uint64_t frame_index, cv::Mat* sensor,
                             const cv::Rect& sensor_region) {
  const int radius = MotionBlurRadiusPx(blur_px);
  if (radius == 0) {
    ApplyOptics(pinhole, frame_index, sensor, sensor_region);
    return;
  }
  // fast motion blur: the region (grown by the smear) is convolved with a line kernel along
  // the image motion, centred on the mid-exposure position
  const double length_px = blur_px.norm();
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
  // the smear is full over the payload's image and its own smear (the core) and fades out
  // linearly over a band around it: the background meets the unblurred image without a seam.
  // The weights depend only on the whole frame's geometry, so a region equals the whole frame.
  const bool whole = blur_region.area() == 0;
  const cv::Rect core =
      whole ? frame
            : cv::Rect(blur_region.x - radius, blur_region.y - radius,
                       blur_region.width + 2 * radius, blur_region.height + 2 * radius);
  const int fade_px = std::max(kMinBlurFadePx, 4 * radius);
  const cv::Rect outer = whole ? frame
                               : cv::Rect(core.x - fade_px, core.y - fade_px,
                                          core.width + 2 * fade_px, core.height + 2 * fade_px);
  // only what the optics will read: the render region of the sensor region
  const cv::Rect source = RenderRegion(sensor_region, Eigen::Vector2d::Zero());
  blurred_.create(pinhole.size(), pinhole.type());
  cv::Mat blurred_source = blurred_(source);
  pinhole(source).copyTo(blurred_source);
  const cv::Rect region = outer & frame & source;
  if (region.area() > 0) {
    cv::Mat target = blurred_(region);
    cv::filter2D(pinhole(region), target, -1, kernel, cv::Point(-1, -1), 0.0, cv::BORDER_REPLICATE);
    if (!whole) {
      const int channels = pinhole.channels();
      for (int row = region.y; row < region.y + region.height; ++row) {
        const int dy = std::max({core.y - row, row - (core.y + core.height - 1), 0});
        const uint8_t* sharp = pinhole.ptr<uint8_t>(row);
        uint8_t* out = blurred_.ptr<uint8_t>(row);
        for (int col = region.x; col < region.x + region.width; ++col) {
          const int dx = std::max({core.x - col, col - (core.x + core.width - 1), 0});
          const int d = std::max(dx, dy);  // pixels outside the core
          if (d == 0) continue;
          const float w = std::max(0.0f, 1.0f - static_cast<float>(d) / (fade_px + 1));
          for (int c = col * channels; c < (col + 1) * channels; ++c) {
            out[c] = cv::saturate_cast<uint8_t>(w * out[c] + (1.0f - w) * sharp[c]);
          }
        }
      }
    }
  }
  ApplyOptics(blurred_, frame_index, sensor, sensor_region);
}

}  // namespace hpa::sim
