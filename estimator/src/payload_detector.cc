#include "hpa/estimator/payload_detector.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "hpa/models/camera_model.h"

namespace hpa {
namespace {

PayloadDetection NotFound(double time_s, const char* reason) {
  PayloadDetection d;
  d.time_s = time_s;
  d.found = false;
  d.reason = reason;
  return d;
}

}  // namespace

PayloadDetector::PayloadDetector(const Params& params, const PayloadDetectorConfig& config)
    : params_(params), config_(config) {}

PayloadDetection PayloadDetector::Detect(const cv::Mat& bgr, double time_s) const {
  bool inside = true;
  return DetectInArea(bgr, cv::Rect(0, 0, params_.camera_width_px, params_.camera_height_px),
                      time_s, &inside);
}

std::optional<PayloadDetection> PayloadDetector::DetectInRegion(const cv::Mat& bgr,
                                                                const cv::Rect& region,
                                                                double time_s) const {
  const cv::Rect area = region & cv::Rect(0, 0, params_.camera_width_px, params_.camera_height_px);
  if (area.width < 8 || area.height < 8) return std::nullopt;
  bool inside = false;
  const PayloadDetection d = DetectInArea(bgr, area, time_s, &inside);
  if (!inside || !d.found) return std::nullopt;
  return d;
}

cv::Rect PayloadDetector::RegionAround(const PayloadDetection& last, double margin_px) const {
  if (!last.found || !last.centre_px.allFinite() || !std::isfinite(last.radius_px)) return {};
  // the last ideal-image centre, where the lens puts it, and a half size of the ball's radius
  // (grown for the ellipse of an off-axis ball) plus the motion allowed between frames
  const Eigen::Vector2d c = DistortPixel(params_, last.centre_px);
  const double half = 1.5 * last.radius_px + margin_px;
  if (!c.allFinite() || !(half > 0.0) || half > params_.camera_width_px) return {};
  const int x0 = static_cast<int>(std::floor(c.x() - half));
  const int y0 = static_cast<int>(std::floor(c.y() - half));
  const int size = static_cast<int>(std::ceil(2.0 * half));
  return cv::Rect(x0, y0, size, size) &
         cv::Rect(0, 0, params_.camera_width_px, params_.camera_height_px);
}

PayloadDetection PayloadDetector::DetectInArea(const cv::Mat& bgr, const cv::Rect& area,
                                               double time_s, bool* inside_area) const {
  const int width = params_.camera_width_px, height = params_.camera_height_px;
  *inside_area = false;
  if (bgr.empty() || bgr.type() != CV_8UC3 || bgr.cols != width || bgr.rows != height) {
    return NotFound(time_s, "bad frame (expected 8-bit BGR of the camera's size)");
  }
  const cv::Point origin = area.tl();  // work images cover `area`; their (0, 0) is here

  // red mask: saturated pixels in the two red hue bands
  // frame-sized buffers are members: reused from call to call, no per-frame allocation
  cv::Mat& hsv = buffers_.hsv;
  cv::Mat& mask_low = buffers_.mask_low;
  cv::Mat& mask_high = buffers_.mask_high;
  cv::Mat& mask = buffers_.mask;
  cv::cvtColor(bgr(area), hsv, cv::COLOR_BGR2HSV);
  cv::inRange(hsv, cv::Scalar(0, config_.saturation_min, config_.value_min),
              cv::Scalar(config_.hue_max_low, 255, 255), mask_low);
  cv::inRange(hsv, cv::Scalar(config_.hue_min_high, config_.saturation_min, config_.value_min),
              cv::Scalar(180, 255, 255), mask_high);
  cv::bitwise_or(mask_low, mask_high, mask);

  // largest blob
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE, origin);
  if (contours.empty()) return NotFound(time_s, "no payload in view");
  int best = 0;
  double best_area_px2 = -1.0;
  for (int i = 0; i < static_cast<int>(contours.size()); ++i) {
    const double area_px2 = cv::contourArea(contours[i]);
    if (area_px2 > best_area_px2) {
      best_area_px2 = area_px2;
      best = i;
    }
  }
  const std::vector<cv::Point>& contour = contours[best];
  if (best_area_px2 < config_.min_area_px2) return NotFound(time_s, "too small");

  // occluders: very dark pixels (the cable seen from a camera next to it is a black wedge);
  // where they touch the blob, its outline is not the sphere's and must not be fitted
  cv::Mat& occluder = buffers_.occluder;
  cv::inRange(hsv, cv::Scalar(0, 0, 0), cv::Scalar(180, 255, config_.occluder_value_max), occluder);
  const cv::Rect image_rect(0, 0, width, height);
  const int grow_px = config_.occluder_grow_px;
  const cv::Rect blob_rect = cv::boundingRect(contour);
  // a region's result stands only where everything it reads lies inside it, so that it equals
  // the full frame's: the blob with the occluder growth and the dilation's own reach
  const int reach_px = 2 * grow_px + 2;
  const auto inside = [&](const cv::Rect& r) {
    const cv::Rect need =
        cv::Rect(r.x - reach_px, r.y - reach_px, r.width + 2 * reach_px, r.height + 2 * reach_px) &
        image_rect;
    return (need & area) == need;
  };
  if (!inside(blob_rect)) return NotFound(time_s, "payload at the region's edge");
  const cv::Rect near_blob(blob_rect.x - grow_px, blob_rect.y - grow_px,
                           blob_rect.width + 2 * grow_px, blob_rect.height + 2 * grow_px);
  const cv::Rect near_blob_in = near_blob & image_rect;
  cv::Mat& occluded_near = buffers_.occluded_near;
  occluded_near.create(area.height, area.width, CV_8U);
  occluded_near.setTo(0);
  cv::dilate(occluder(near_blob_in - origin), occluded_near(near_blob_in - origin),
             cv::Mat::ones(2 * grow_px + 1, 2 * grow_px + 1, CV_8U));

  // outline points that are neither on the image border nor next to an occluder
  std::vector<cv::Point2f> outline;
  outline.reserve(contour.size());
  for (const cv::Point& p : contour) {
    if (p.x > 0 && p.y > 0 && p.x < width - 1 && p.y < height - 1 &&
        occluded_near.at<uint8_t>(p - origin) == 0) {
      outline.emplace_back(p);
    }
  }
  if (outline.size() < config_.min_fit_share * contour.size() ||
      outline.size() < static_cast<size_t>(config_.min_fit_points)) {
    return NotFound(time_s, "partly out of view");
  }
  // the fit in the real (distorted) image: checks of the blob against the fitted ellipse
  const cv::RotatedRect fit = cv::fitEllipseDirect(outline);
  const double semi_major_px =
      0.5 * std::max(fit.size.width, fit.size.height) + config_.edge_bias_px;
  const double semi_minor_px =
      0.5 * std::min(fit.size.width, fit.size.height) + config_.edge_bias_px;
  if (!std::isfinite(semi_major_px) || !std::isfinite(semi_minor_px) ||
      semi_minor_px < config_.min_semi_minor_px || semi_major_px > 2.0 * std::max(width, height)) {
    return NotFound(time_s, "poor ellipse fit");
  }
  // OpenCV puts pixel centres on integers; continuous coordinates put them at +0.5
  const Eigen::Vector2d centre_px(fit.center.x + 0.5, fit.center.y + 0.5);
  const double angle_rad = fit.angle * M_PI / 180.0;
  const Eigen::Vector2d width_axis(std::cos(angle_rad), std::sin(angle_rad));
  const Eigen::Vector2d major_axis = fit.size.width >= fit.size.height
                                         ? width_axis
                                         : Eigen::Vector2d(-width_axis.y(), width_axis.x());

  // region where the blob and the fitted ellipse are compared; occluders grown there too
  if (!inside(fit.boundingRect())) return NotFound(time_s, "payload at the region's edge");
  const cv::Rect roi = (blob_rect | fit.boundingRect()) & image_rect;
  cv::Mat occluded_roi;
  cv::dilate(occluder(roi - origin), occluded_roi,
             cv::Mat::ones(2 * grow_px + 1, 2 * grow_px + 1, CV_8U));

  // enough of the fitted outline must be seen: inside the image and not behind an occluder
  const int outline_samples = config_.outline_samples;
  const Eigen::Vector2d minor_axis(-major_axis.y(), major_axis.x());
  int seen = 0;
  for (int i = 0; i < outline_samples; ++i) {
    const double phi = 2.0 * M_PI * i / outline_samples;
    const Eigen::Vector2d q = centre_px + semi_major_px * std::cos(phi) * major_axis +
                              semi_minor_px * std::sin(phi) * minor_axis;
    if (q.x() < 1.0 || q.y() < 1.0 || q.x() > width - 1.0 || q.y() > height - 1.0) continue;
    const cv::Point pixel(static_cast<int>(q.x()), static_cast<int>(q.y()));
    if (!roi.contains(pixel) || occluded_roi.at<uint8_t>(pixel - roi.tl()) == 0) ++seen;
  }
  if (seen < config_.min_visible_outline * outline_samples) {
    return NotFound(time_s, "partly out of view");
  }

  // the blob must agree with the fitted ellipse (clipped to the image, occluders left out):
  // intersection over union
  cv::Mat blob_mask = cv::Mat::zeros(roi.size(), CV_8U);
  cv::Mat ellipse_mask = cv::Mat::zeros(roi.size(), CV_8U);
  cv::drawContours(blob_mask, contours, best, cv::Scalar(255), cv::FILLED, cv::LINE_8,
                   cv::noArray(), 0, -roi.tl());
  cv::RotatedRect shifted = fit;
  shifted.center -= cv::Point2f(roi.x, roi.y);
  cv::ellipse(ellipse_mask, shifted, cv::Scalar(255), cv::FILLED, cv::LINE_8);
  cv::Mat both, either, visible;
  cv::bitwise_not(occluded_roi, visible);
  cv::bitwise_and(blob_mask, ellipse_mask, both, visible);
  cv::bitwise_or(blob_mask, ellipse_mask, either);
  cv::bitwise_and(either, visible, either);
  const double iou =
      static_cast<double>(cv::countNonZero(both)) / std::max(1, cv::countNonZero(either));
  if (iou < config_.min_iou) return NotFound(time_s, "poor ellipse fit");

  // with a distorted lens, the outline is undistorted to the pinhole image (where a sphere's
  // image is an exact ellipse) and fitted again there
  Eigen::Vector2d ideal_centre_px = centre_px;
  double ideal_semi_major_px = semi_major_px, ideal_semi_minor_px = semi_minor_px;
  Eigen::Vector2d ideal_major_axis = major_axis;
  if (!params_.camera_distortion.isZero()) {
    undistorted_.clear();
    for (const cv::Point2f& p : outline) {
      // contour points are pixel indices: continuous coordinates are +0.5
      const Eigen::Vector2d q = UndistortPixel(params_, Eigen::Vector2d(p.x + 0.5, p.y + 0.5));
      undistorted_.emplace_back(static_cast<float>(q.x() - 0.5), static_cast<float>(q.y() - 0.5));
    }
    const cv::RotatedRect ideal = cv::fitEllipseDirect(undistorted_);
    // the edge bias is a pixel-scale effect: scaled by the lens's local magnification
    const double magnification =
        std::max(ideal.size.width, ideal.size.height) / std::max(fit.size.width, fit.size.height);
    ideal_semi_major_px =
        0.5 * std::max(ideal.size.width, ideal.size.height) + config_.edge_bias_px * magnification;
    ideal_semi_minor_px =
        0.5 * std::min(ideal.size.width, ideal.size.height) + config_.edge_bias_px * magnification;
    ideal_centre_px = Eigen::Vector2d(ideal.center.x + 0.5, ideal.center.y + 0.5);
    const double a_rad = ideal.angle * M_PI / 180.0;
    const Eigen::Vector2d w_axis(std::cos(a_rad), std::sin(a_rad));
    ideal_major_axis =
        ideal.size.width >= ideal.size.height ? w_axis : Eigen::Vector2d(-w_axis.y(), w_axis.x());
    if (!ideal_centre_px.allFinite() || !std::isfinite(ideal_semi_major_px)) {
      return NotFound(time_s, "poor ellipse fit");
    }
  }

  // major axis of a sphere's image lies on the line through the principal point
  const Eigen::Vector2d principal_px(0.5 * width, 0.5 * height);
  const Eigen::Vector2d radial = ideal_centre_px - principal_px;
  const Eigen::Vector2d axis = radial.norm() > config_.min_radial_offset_px
                                   ? Eigen::Vector2d(radial.normalized())
                                   : ideal_major_axis;
  const Eigen::Vector3d p_CL_C = SphereCentreFromMajorAxis(
      params_, ideal_centre_px + ideal_semi_major_px * axis,
      ideal_centre_px - ideal_semi_major_px * axis, params_.payload_radius_m);
  if (!p_CL_C.allFinite()) return NotFound(time_s, "poor ellipse fit");

  *inside_area = true;
  PayloadDetection detection;
  detection.time_s = time_s;
  detection.found = true;
  detection.p_CL_C = p_CL_C;
  detection.centre_px = ideal_centre_px;
  detection.radius_px = ideal_semi_minor_px;
  return detection;
}

}  // namespace hpa
