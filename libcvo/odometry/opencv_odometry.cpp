#include "libcvo/odometry/opencv_odometry.hpp"

#include "libcvo/core/units.hpp"
#include "libcvo/odometry/motion_model.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/rgbd.hpp>

namespace cvo::odometry {

namespace {

using Clock = core::SteadyClock;
using core::ms_since;
using cv::rgbd::OdometryFrame;

// As in frame_to_frame.cpp: V^s = exp(s log V), and the frames between two stream indices (1 when
// they do not increase).

cv::Mat to_cv(const core::SE3& transform) {
  const Eigen::Matrix4d m = transform.matrix();
  cv::Mat out(4, 4, CV_64FC1);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out.at<double>(r, c) = m(r, c);
  return out;
}

// nullopt when the matrix is not a finite 4x4 CV_64FC1.
std::optional<core::SE3> from_cv(const cv::Mat& rt) {
  if (rt.rows != 4 || rt.cols != 4 || rt.type() != CV_64FC1 || !cv::checkRange(rt)) return std::nullopt;
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m(r, c) = rt.at<double>(r, c);
  const core::SE3 t(m);
  if (!t.is_finite()) return std::nullopt;
  return t;
}

int count(const std::vector<cv::Mat>& pyramid) { return pyramid.empty() ? 0 : cv::countNonZero(pyramid[0]); }

}  // namespace

const char* to_string(OpenCvVariant variant) {
  switch (variant) {
    case OpenCvVariant::rgbd: return "rgbd";
    case OpenCvVariant::rgbd_icp: return "rgbd_icp";
  }
  return "unknown";
}

struct OpenCvOdometry::State {
  OpenCvOdometryParameters parameters;
  core::Intrinsics camera;
  cv::Ptr<cv::rgbd::Odometry> odometry;
  std::array<cv::Ptr<OdometryFrame>, 2> frames;  // slots of `motion`: reference and current
  MotionModel motion;

  // Converts `frame` into frames[slot] and prepares its cache for both roles. Returns the
  // selection status; on kOk `points` holds the pixels OpenCV samples in it.
  registration::SelectionStatus prepare(const core::RgbdFrame& frame, int slot, std::size_t& points);
};

registration::SelectionStatus OpenCvOdometry::State::prepare(const core::RgbdFrame& frame, int slot,
                                                             std::size_t& points) {
  using registration::SelectionStatus;
  if (frame.bgr.empty() || frame.depth.empty() || frame.bgr.cols != camera.width || frame.bgr.rows != camera.height ||
      frame.depth.size() != frame.bgr.size())
    return SelectionStatus::kEmptyFrame;
  if (frame.bgr.type() != CV_8UC3 || frame.depth.type() != CV_16UC1) return SelectionStatus::kBadImageType;

  cv::Ptr<OdometryFrame>& f = frames[static_cast<std::size_t>(slot)];
  if (!f) f = cv::makePtr<OdometryFrame>();
  // prepareFrameCache() keeps whatever cache a frame already has, so all of it goes; the image and
  // depth buffers are reused (no pyramid shares them once the pyramids are released).
  f->releasePyramids();
  f->mask.release();
  f->normals.release();
  cv::cvtColor(frame.bgr, f->image, cv::COLOR_BGR2GRAY);
  frame.depth.convertTo(f->depth, CV_32FC1, 1.0 / camera.depth_scale);
  f->depth.setTo(std::numeric_limits<float>::quiet_NaN(), frame.depth == 0);
  odometry->prepareFrameCache(f, OdometryFrame::CACHE_ALL);
  if (count(f->pyramidMask) == 0) return SelectionStatus::kNoValidDepth;
  points = static_cast<std::size_t>(count(f->pyramidTexturedMask) + count(f->pyramidNormalsMask));
  return SelectionStatus::kOk;
}

OpenCvOdometry::OpenCvOdometry(const core::Intrinsics& camera, const OpenCvOdometryParameters& parameters)
    : state_(std::make_unique<State>(
          State{parameters,
                camera,
                {},
                {},
                MotionModel(parameters.initial_pose, parameters.odometry.restart_after_failures)})) {
  State& s = *state_;
  // CV_32FC1 as OpenCV's own sample: RgbdICPOdometry compares it with its normals computer's K.
  const cv::Mat k = (cv::Mat_<float>(3, 3) << static_cast<float>(camera.fx), 0.f, static_cast<float>(camera.cx), 0.f,
                     static_cast<float>(camera.fy), static_cast<float>(camera.cy), 0.f, 0.f, 1.f);
  const auto min_depth = static_cast<float>(parameters.selection.min_depth_m);
  const auto max_depth = static_cast<float>(parameters.selection.max_depth_m);
  if (parameters.variant == OpenCvVariant::rgbd)
    s.odometry = cv::rgbd::RgbdOdometry::create(k, min_depth, max_depth);
  else
    s.odometry = cv::rgbd::RgbdICPOdometry::create(k, min_depth, max_depth);
}

OpenCvOdometry::~OpenCvOdometry() = default;
OpenCvOdometry::OpenCvOdometry(OpenCvOdometry&&) noexcept = default;
OpenCvOdometry& OpenCvOdometry::operator=(OpenCvOdometry&&) noexcept = default;

const OpenCvOdometryParameters& OpenCvOdometry::parameters() const { return state_->parameters; }

TrackResult OpenCvOdometry::track(const core::RgbdFrame& frame) {
  State& s = *state_;
  TrackResult result;
  const core::SE3 predicted = s.motion.predict(frame.index);
  const int current = s.motion.current_slot();
  const auto selection_start = Clock::now();
  try {
    result.selection_status = s.prepare(frame, current, result.points);
  } catch (const cv::Exception&) {
    result.selection_status = registration::SelectionStatus::kEmptyFrame;  // checked above: not expected
  }
  result.selection_ms = ms_since(selection_start);

  core::SE3 measured;
  if (result.selection_status != registration::SelectionStatus::kOk) {
    result.status = TrackStatus::kSelectionFailed;
    result.points = 0;
  } else if (!s.motion.has_reference()) {
    result.status = TrackStatus::kFirstFrame;
  } else {
    const cv::Mat initial_rt = to_cv(s.motion.guess(predicted).inverse());  // OpenCV's Rt: p_k = Rt p_r
    cv::Mat rt;
    bool ok = false;
    const auto registration_start = Clock::now();
    try {
      ok = s.odometry->compute(s.frames[static_cast<std::size_t>(s.motion.reference_slot())],
                               s.frames[static_cast<std::size_t>(current)], rt, initial_rt);
    } catch (const cv::Exception&) {
      ok = false;
      rt.release();
    }
    result.registration_ms = ms_since(registration_start);
    const std::optional<core::SE3> rt_pose = ok ? from_cv(rt) : std::nullopt;
    if (rt_pose) {
      measured = rt_pose->inverse();  // T_r_k
      result.status = TrackStatus::kOk;
      result.registration_status = registration::RegistrationStatus::kOk;
    } else {
      result.status = TrackStatus::kRegistrationFailed;
      // No step taken (too few correspondences, singular system, or OpenCV threw) or a step that
      // OpenCV itself rejected as implausible (beyond 0.15 m / 15 deg from the guess).
      const bool stepped = !rt.empty() && rt.size() == initial_rt.size() && rt.type() == initial_rt.type() &&
                           cv::norm(rt, initial_rt, cv::NORM_INF) > 0;
      result.registration_status =
          stepped ? registration::RegistrationStatus::kNotConverged : registration::RegistrationStatus::kNoOverlap;
    }
  }
  s.motion.update(frame.index, predicted, measured, result);
  return result;
}

}  // namespace cvo::odometry
