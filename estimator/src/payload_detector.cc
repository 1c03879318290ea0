#include "hpa/estimator/payload_detector.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <vector>

#include "hpa/estimator/payload_masks.h"
#include "hpa/models/camera_model.h"

namespace hpa {
namespace {

// A frame without a detection, and why (a reason instead of a guess).
PayloadDetection NotFound(double time_s, const char* reason) {
  PayloadDetection d;
  d.time_s = time_s;
  d.found = false;
  d.reason = reason;
  return d;
}

// An ellipse in continuous pixel coordinates (pixel centres at +0.5): centre, semi-axes and the
// unit direction of its major axis.
struct Ellipse {
  Eigen::Vector2d centre_px = Eigen::Vector2d::Zero();
  double semi_major_px = 0.0;
  double semi_minor_px = 0.0;
  Eigen::Vector2d major_axis = Eigen::Vector2d::UnitX();
};

// The ellipse OpenCV fitted, in continuous coordinates (OpenCV puts pixel centres on integers),
// its semi-axes grown by edge_bias_px: the contour runs through the edge pixels' centres.
Ellipse FromFit(const cv::RotatedRect& fit, double edge_bias_px) {
  Ellipse e;
  e.semi_major_px = 0.5 * std::max(fit.size.width, fit.size.height) + edge_bias_px;
  e.semi_minor_px = 0.5 * std::min(fit.size.width, fit.size.height) + edge_bias_px;
  e.centre_px = Eigen::Vector2d(fit.center.x + 0.5, fit.center.y + 0.5);
  const double angle_rad = fit.angle * M_PI / 180.0;
  const Eigen::Vector2d width_axis(std::cos(angle_rad), std::sin(angle_rad));
  e.major_axis = fit.size.width >= fit.size.height
                     ? width_axis
                     : Eigen::Vector2d(-width_axis.y(), width_axis.x());
  return e;
}

// The detection of a payload centred at p_CL_C, its ellipse in the ideal image.
PayloadDetection Found(double time_s, const Eigen::Vector3d& p_CL_C, const Ellipse& ideal) {
  PayloadDetection detection;
  detection.time_s = time_s;
  detection.found = true;
  detection.p_CL_C = p_CL_C;
  detection.centre_px = ideal.centre_px;
  detection.radius_px = ideal.semi_minor_px;
  return detection;
}

// Whether the fitted ellipse has a plausible size: finite, a semi-minor axis of at least
// min_semi_minor_px and a semi-major axis of at most twice the image's larger side.
bool PlausibleSize(const Ellipse& fitted, double min_semi_minor_px, int width_px, int height_px) {
  return std::isfinite(fitted.semi_major_px) && std::isfinite(fitted.semi_minor_px) &&
         !(fitted.semi_minor_px < min_semi_minor_px) &&
         !(fitted.semi_major_px > 2.0 * std::max(width_px, height_px));
}

// Index of the contour of largest area (the payload is the largest red object in view) and that
// area in *area_px2.
int LargestContour(const std::vector<std::vector<cv::Point>>& contours, double* area_px2) {
  int best = 0;
  double best_area_px2 = -1.0;
  for (int i = 0; i < static_cast<int>(contours.size()); ++i) {
    const double contour_area_px2 = cv::contourArea(contours[i]);
    if (contour_area_px2 > best_area_px2) {
      best_area_px2 = contour_area_px2;
      best = i;
    }
  }
  *area_px2 = best_area_px2;
  return best;
}

// Whether everything read for the image part `r` (r grown by reach_px, clipped to the image)
// lies inside the work area: only then does a region's result equal the full frame's.
bool ReadsInside(const cv::Rect& r, int reach_px, const cv::Rect& area,
                 const cv::Rect& image_rect) {
  const cv::Rect need =
      cv::Rect(r.x - reach_px, r.y - reach_px, r.width + 2 * reach_px, r.height + 2 * reach_px) &
      image_rect;
  return (need & area) == need;
}

// The occluder mask grown by grow_px (a dilation), computed only over the blob's box grown by
// grow_px and zero elsewhere: *occluded_near covers the work area `area` (a reused buffer).
void GrowOccludersNearBlob(const cv::Mat& occluder, const cv::Rect& blob_rect, int grow_px,
                           const cv::Rect& area, const cv::Rect& image_rect,
                           cv::Mat* occluded_near) {
  const cv::Point origin = area.tl();
  const cv::Rect near_blob(blob_rect.x - grow_px, blob_rect.y - grow_px,
                           blob_rect.width + 2 * grow_px, blob_rect.height + 2 * grow_px);
  const cv::Rect near_blob_in = near_blob & image_rect;
  occluded_near->create(area.height, area.width, CV_8U);
  occluded_near->setTo(0);
  cv::dilate(occluder(near_blob_in - origin), (*occluded_near)(near_blob_in - origin),
             cv::Mat::ones(2 * grow_px + 1, 2 * grow_px + 1, CV_8U));
}

// Outline points to fit: neither on the image border nor next to an occluder (occluded_near
// covers the work area whose (0, 0) is at `origin`), where the outline is not the sphere's.
std::vector<cv::Point2f> FittableOutline(const std::vector<cv::Point>& contour,
                                         const cv::Mat& occluded_near, const cv::Point& origin,
                                         int width_px, int height_px) {
  std::vector<cv::Point2f> outline;
  outline.reserve(contour.size());
  for (const cv::Point& p : contour) {
    if (p.x > 0 && p.y > 0 && p.x < width_px - 1 && p.y < height_px - 1 &&
        occluded_near.at<uint8_t>(p - origin) == 0) {
      outline.emplace_back(p);
    }
  }
  return outline;
}

// How many of outline_samples points on the fitted outline are seen: inside the image and not on
// an occluder (occluded_roi: the grown occluders of `roi`); a payload mostly out of view or
// behind the cable is not trusted.
int SeenOutlineSamples(const Ellipse& fitted, int outline_samples, const cv::Rect& roi,
                       const cv::Mat& occluded_roi, int width_px, int height_px) {
  const Eigen::Vector2d minor_axis(-fitted.major_axis.y(), fitted.major_axis.x());
  int seen = 0;
  for (int i = 0; i < outline_samples; ++i) {
    const double phi = 2.0 * M_PI * i / outline_samples;
    const Eigen::Vector2d q = fitted.centre_px +
                              fitted.semi_major_px * std::cos(phi) * fitted.major_axis +
                              fitted.semi_minor_px * std::sin(phi) * minor_axis;
    if (q.x() < 1.0 || q.y() < 1.0 || q.x() > width_px - 1.0 || q.y() > height_px - 1.0) continue;
    const cv::Point pixel(static_cast<int>(q.x()), static_cast<int>(q.y()));
    if (!roi.contains(pixel) || occluded_roi.at<uint8_t>(pixel - roi.tl()) == 0) ++seen;
  }
  return seen;
}

// Intersection over union of the blob (contours[best]) and the fitted ellipse inside `roi`,
// occluded pixels left out: how well the blob agrees with the ellipse.
double BlobEllipseIou(const std::vector<std::vector<cv::Point>>& contours, int best,
                      const cv::RotatedRect& fit, const cv::Rect& roi,
                      const cv::Mat& occluded_roi) {
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
  return static_cast<double>(cv::countNonZero(both)) / std::max(1, cv::countNonZero(either));
}

// With a distorted lens: the outline undistorted to the pinhole image (where a sphere's image is
// an exact ellipse) and fitted again there, the edge bias scaled by the lens's local
// magnification (it is a pixel-scale effect); nullopt when that fit is not finite. *undistorted
// is a reused buffer.
std::optional<Ellipse> IdealEllipse(const Params& params, const std::vector<cv::Point2f>& outline,
                                    const cv::RotatedRect& fit, double edge_bias_px,
                                    std::vector<cv::Point2f>* undistorted) {
  undistorted->clear();
  for (const cv::Point2f& p : outline) {
    // contour points are pixel indices: continuous coordinates are +0.5
    const Eigen::Vector2d q = UndistortPixel(params, Eigen::Vector2d(p.x + 0.5, p.y + 0.5));
    undistorted->emplace_back(static_cast<float>(q.x() - 0.5), static_cast<float>(q.y() - 0.5));
  }
  const cv::RotatedRect ideal = cv::fitEllipseDirect(*undistorted);
  const double magnification =
      std::max(ideal.size.width, ideal.size.height) / std::max(fit.size.width, fit.size.height);
  const Ellipse e = FromFit(ideal, edge_bias_px * magnification);
  if (!e.centre_px.allFinite() || !std::isfinite(e.semi_major_px)) return std::nullopt;
  return e;
}

// The payload's centre in the camera frame from its ellipse in the ideal image: the major axis of
// a sphere's image lies on the line through the principal point (closer to it than
// min_radial_offset_px that line is ill-defined: the fitted axis is taken).
Eigen::Vector3d PayloadCentre_C(const Params& params, const Ellipse& ideal,
                                double min_radial_offset_px) {
  const Eigen::Vector2d principal_px(0.5 * params.camera_width_px, 0.5 * params.camera_height_px);
  const Eigen::Vector2d radial = ideal.centre_px - principal_px;
  const Eigen::Vector2d axis = radial.norm() > min_radial_offset_px
                                   ? Eigen::Vector2d(radial.normalized())
                                   : ideal.major_axis;
  return SphereCentreFromMajorAxis(params, ideal.centre_px + ideal.semi_major_px * axis,
                                   ideal.centre_px - ideal.semi_major_px * axis,
                                   params.payload_radius_m);
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

cv::Rect PayloadDetector::RegionAround(const RecentDetections& recent, double margin_px) const {
  const PayloadDetection& last = recent.last;
  const PayloadDetection& previous = recent.previous;
  if (!last.found || !last.centre_px.allFinite() || !std::isfinite(last.radius_px)) return {};
  // the last ideal-image centre, where the lens puts it, and a half size of the ball's radius
  // (grown for the ellipse of an off-axis ball) plus the motion allowed between frames
  Eigen::Vector2d c = DistortPixel(params_, last.centre_px);
  double allowance_px = margin_px;
  // with the frame before (consecutive frames are evenly spaced), the ball moves on as it moved:
  // the centre predicted, half the margin plus half the motion left for its change
  if (previous.found && previous.centre_px.allFinite() && previous.time_s < last.time_s) {
    const Eigen::Vector2d motion_px = c - DistortPixel(params_, previous.centre_px);
    if (motion_px.allFinite()) {
      c += motion_px;
      allowance_px = 0.5 * margin_px + 0.5 * motion_px.norm();
    }
  }
  const double half = 1.5 * last.radius_px + allowance_px;
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

  // red mask and occluder mask (very dark pixels: the cable seen from a camera next to it is a
  // black wedge), then the red mask's largest blob; frame-sized buffers are members: reused from
  // call to call, no per-frame allocation
  PayloadMasks(bgr(area), config_.masks, &buffers_.mask, &buffers_.occluder);
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(buffers_.mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE, origin);
  if (contours.empty()) return NotFound(time_s, "no payload in view");
  double best_area_px2 = 0.0;
  const int best = LargestContour(contours, &best_area_px2);
  const std::vector<cv::Point>& contour = contours[best];
  if (best_area_px2 < config_.min_area_px2) return NotFound(time_s, "too small");

  // where occluders touch the blob, its outline is not the sphere's and must not be fitted
  const cv::Mat& occluder = buffers_.occluder;
  const cv::Rect image_rect(0, 0, width, height);
  const int grow_px = config_.occluder_grow_px;
  const cv::Rect blob_rect = cv::boundingRect(contour);
  // a region's result stands only where everything it reads lies inside it, so that it equals
  // the full frame's: the blob with the occluder growth and the dilation's own reach
  const int reach_px = 2 * grow_px + 2;
  if (!ReadsInside(blob_rect, reach_px, area, image_rect)) {
    return NotFound(time_s, "payload at the region's edge");
  }
  cv::Mat& occluded_near = buffers_.occluded_near;
  GrowOccludersNearBlob(occluder, blob_rect, grow_px, area, image_rect, &occluded_near);

  const std::vector<cv::Point2f> outline =
      FittableOutline(contour, occluded_near, origin, width, height);
  if (outline.size() < config_.min_fit_share * contour.size() ||
      outline.size() < static_cast<size_t>(config_.min_fit_points)) {
    return NotFound(time_s, "partly out of view");
  }
  // the fit in the real (distorted) image: checks of the blob against the fitted ellipse
  const cv::RotatedRect fit = cv::fitEllipseDirect(outline);
  const Ellipse fitted = FromFit(fit, config_.edge_bias_px);
  if (!PlausibleSize(fitted, config_.min_semi_minor_px, width, height)) {
    return NotFound(time_s, "poor ellipse fit");
  }

  // region where the blob and the fitted ellipse are compared; occluders grown there too
  if (!ReadsInside(fit.boundingRect(), reach_px, area, image_rect)) {
    return NotFound(time_s, "payload at the region's edge");
  }
  const cv::Rect roi = (blob_rect | fit.boundingRect()) & image_rect;
  cv::Mat occluded_roi;
  cv::dilate(occluder(roi - origin), occluded_roi,
             cv::Mat::ones(2 * grow_px + 1, 2 * grow_px + 1, CV_8U));
  // enough of the fitted outline must be seen, and the blob must agree with the ellipse
  const int seen =
      SeenOutlineSamples(fitted, config_.outline_samples, roi, occluded_roi, width, height);
  if (seen < config_.min_visible_outline * config_.outline_samples) {
    return NotFound(time_s, "partly out of view");
  }
  if (BlobEllipseIou(contours, best, fit, roi, occluded_roi) < config_.min_iou) {
    return NotFound(time_s, "poor ellipse fit");
  }

  // the ellipse in the ideal (pinhole) image: the fit itself without lens distortion
  const std::optional<Ellipse> ideal =
      params_.camera_distortion.isZero()
          ? std::optional<Ellipse>(fitted)
          : IdealEllipse(params_, outline, fit, config_.edge_bias_px, &undistorted_);
  if (!ideal) return NotFound(time_s, "poor ellipse fit");
  const Eigen::Vector3d p_CL_C = PayloadCentre_C(params_, *ideal, config_.min_radial_offset_px);
  if (!p_CL_C.allFinite()) return NotFound(time_s, "poor ellipse fit");
  *inside_area = true;
  return Found(time_s, p_CL_C, *ideal);
}

}  // namespace hpa
