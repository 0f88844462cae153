#include "libcvo/registration/point_selection.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "libcvo/core/pixel_rays.hpp"

namespace cvo::registration {
namespace {

// A point of row v moved to the frame's time (see PointSelector::select): P + τ(v) (ω × P + v).
class RollingShutter {
 public:
  RollingShutter(const core::Intrinsics& K, const core::Vector6d& twist)
      : on_(K.rolling_shutter() && K.height > 1 && twist.allFinite() && !twist.isZero()),
        seconds_per_row_(static_cast<float>(K.readout_s / (K.height - 1))),
        middle_row_(0.5f * static_cast<float>(K.height - 1)),
        v_(twist.head<3>().cast<float>()), w_(twist.tail<3>().cast<float>()) {}

  [[nodiscard]] Eigen::Vector3f at_frame_time(const Eigen::Vector3f& P, int row) const {
    if (!on_) return P;
    const float tau = seconds_per_row_ * (static_cast<float>(row) - middle_row_);
    return P + tau * (w_.cross(P) + v_);
  }

 private:
  bool on_;
  float seconds_per_row_, middle_row_;
  Eigen::Vector3f v_, w_;
};

constexpr int kRegion = 32;           // DSO's threshold region size (pixels)
constexpr int kHistogramBins = 50;    // |g| on the 0-255 scale, clipped
constexpr float kThresholdOffset = 7.0f / 255.0f;  // DSO's constant above the median
constexpr int kMaxCellSize = 64;

// The fields the ray table depends on.
bool same_rays(const core::Intrinsics& a, const core::Intrinsics& b) {
  return a.fx == b.fx && a.fy == b.fy && a.cx == b.cx && a.cy == b.cy && a.distortion == b.distortion;
}

}  // namespace

const char* to_string(SelectionStatus status) {
  switch (status) {
    case SelectionStatus::kOk: return "ok";
    case SelectionStatus::kEmptyFrame: return "empty frame or size mismatch";
    case SelectionStatus::kBadImageType: return "colour must be CV_8UC3 and depth CV_16UC1";
    case SelectionStatus::kNoValidDepth: return "no valid depth";
    case SelectionStatus::kCapacityClamped: return "point capacity reached, points dropped";
  }
  return "unknown";
}

PointSelector::PointSelector(int width, int height, const core::SelectionParameters& parameters)
    : width_(width), height_(height), parameters_(parameters),
      regions_x_((width + kRegion - 1) / kRegion), regions_y_((height + kRegion - 1) / kRegion) {
  const auto n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  grey_.resize(n);
  // Per-channel tables of w_c · value / 255: three loads and two adds per pixel instead of three
  // integer-to-float conversions and multiplies.
  constexpr std::array<float, 3> kWeights{0.114f, 0.587f, 0.299f};  // B, G, R (ITU-R 601)
  for (std::size_t c = 0; c < 3; ++c)
    for (std::size_t v = 0; v < 256; ++v) grey_lut_[256 * c + v] = kWeights[c] * static_cast<float>(v) / 255.0f;
  magnitude_.assign(n, 0.0f);  // borders stay zero: they are never candidates
  region_threshold_.resize(static_cast<std::size_t>(regions_x_ * regions_y_));
  smoothed_threshold_.resize(region_threshold_.size());
  candidates_.reserve(n);
  cell_best_.resize(n);  // enough for s = 1
}

std::size_t PointSelector::count_for_cell_size(int s) {
  // Keep the strongest candidate of every s x s cell; cell_best_ records the winners.
  const int cells_x = (width_ + s - 1) / s;
  const int cells_y = (height_ + s - 1) / s;
  std::fill_n(cell_best_.begin(), static_cast<std::size_t>(cells_x * cells_y), -1);
  for (std::size_t k = 0; k < candidates_.size(); ++k) {
    const auto p = candidates_[k];
    const int u = static_cast<int>(p % static_cast<std::uint32_t>(width_));
    const int v = static_cast<int>(p / static_cast<std::uint32_t>(width_));
    auto& best = cell_best_[static_cast<std::size_t>((v / s) * cells_x + u / s)];
    if (best < 0 || magnitude_[p] > magnitude_[candidates_[static_cast<std::size_t>(best)]])
      best = static_cast<std::int32_t>(k);
  }
  std::size_t count = 0;
  for (int c = 0; c < cells_x * cells_y; ++c) count += cell_best_[static_cast<std::size_t>(c)] >= 0;
  return count;
}

void PointSelector::build_ray_table(const core::Intrinsics& K) {
  core::Intrinsics sized = K;
  sized.width = width_;
  sized.height = height_;
  rays_ = core::undistorted_pixel_rays(sized);
  ray_intrinsics_ = K;
}

SelectionResult PointSelector::select(const core::RgbdFrame& frame, PointCloud& cloud, const core::SE3& colour_T_depth,
                                      const core::Vector6d& twist) {
  cloud.clear();
  SelectionResult result;
  if (frame.bgr.empty() || frame.depth.empty() || frame.bgr.cols != width_ || frame.bgr.rows != height_ ||
      frame.depth.cols != width_ || frame.depth.rows != height_) {
    result.status = SelectionStatus::kEmptyFrame;
    return result;
  }
  if (frame.bgr.type() != CV_8UC3 || frame.depth.type() != CV_16UC1) {
    result.status = SelectionStatus::kBadImageType;
    return result;
  }
  const auto& K = frame.intrinsics;
  const auto W = static_cast<std::size_t>(width_);

  // 1. Grey image and gradient magnitude. Border pixels keep the zero magnitude set at
  // construction; gx, gy themselves are only needed for the selected points (step 4).
  for (int v = 0; v < height_; ++v) {
    const auto* row = frame.bgr.ptr<std::uint8_t>(v);
    float* grey_row = grey_.data() + static_cast<std::size_t>(v) * W;
    for (int u = 0; u < width_; ++u) {
      const auto* px = row + 3 * u;
      grey_row[u] = grey_lut_[px[0]] + grey_lut_[256 + px[1]] + grey_lut_[512 + px[2]];
    }
  }
  for (int v = 1; v + 1 < height_; ++v) {
    const float* g = grey_.data() + static_cast<std::size_t>(v) * W;
    float* m = magnitude_.data() + static_cast<std::size_t>(v) * W;
    for (int u = 1; u + 1 < width_; ++u) {
      const float gx = g[u + 1] - g[u - 1];  // central difference x 2: range [-1, 1]
      const float gy = g[static_cast<std::ptrdiff_t>(u) + static_cast<std::ptrdiff_t>(W)] -
                       g[static_cast<std::ptrdiff_t>(u) - static_cast<std::ptrdiff_t>(W)];
      m[u] = 0.5f * std::sqrt(gx * gx + gy * gy);
    }
  }

  // 2. Region thresholds: median |g| + offset, smoothed over 3x3 regions.
  for (int ry = 0; ry < regions_y_; ++ry) {
    for (int rx = 0; rx < regions_x_; ++rx) {
      std::array<int, kHistogramBins> histogram{};
      int total = 0;
      for (int v = ry * kRegion; v < std::min(height_, (ry + 1) * kRegion); ++v)
        for (int u = rx * kRegion; u < std::min(width_, (rx + 1) * kRegion); ++u) {
          const float g = magnitude_[static_cast<std::size_t>(v) * W + static_cast<std::size_t>(u)] * 255.0f;
          ++histogram[static_cast<std::size_t>(std::min(kHistogramBins - 1, static_cast<int>(g)))];
          ++total;
        }
      int bin = 0;
      for (int acc = 0; bin < kHistogramBins - 1; ++bin) {
        acc += histogram[static_cast<std::size_t>(bin)];
        if (2 * acc >= total) break;
      }
      region_threshold_[static_cast<std::size_t>(ry * regions_x_ + rx)] =
          (static_cast<float>(bin) + 0.5f) / 255.0f + kThresholdOffset;
    }
  }
  for (int ry = 0; ry < regions_y_; ++ry)
    for (int rx = 0; rx < regions_x_; ++rx) {
      float sum = 0;
      int n = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int x = rx + dx, y = ry + dy;
          if (x < 0 || y < 0 || x >= regions_x_ || y >= regions_y_) continue;
          sum += region_threshold_[static_cast<std::size_t>(y * regions_x_ + x)];
          ++n;
        }
      smoothed_threshold_[static_cast<std::size_t>(ry * regions_x_ + rx)] = sum / static_cast<float>(n);
    }

  // 3. Candidates with valid depth; adapt the cell size to reach the target count.
  const auto min_raw = static_cast<float>(parameters_.min_depth_m * K.depth_scale);
  const auto max_raw = static_cast<float>(parameters_.max_depth_m * K.depth_scale);
  candidates_.clear();
  for (int v = 1; v + 1 < height_; ++v) {
    const auto* depth_row = frame.depth.ptr<std::uint16_t>(v);
    for (int u = 1; u + 1 < width_; ++u) {
      const auto d = static_cast<float>(depth_row[u]);
      if (d <= 0 || d < min_raw || d > max_raw) continue;
      ++result.valid_depth_pixels;
      const std::size_t i = static_cast<std::size_t>(v) * W + static_cast<std::size_t>(u);
      if (magnitude_[i] > smoothed_threshold_[static_cast<std::size_t>((v / kRegion) * regions_x_ + u / kRegion)])
        candidates_.push_back(static_cast<std::uint32_t>(i));
    }
  }
  result.candidates = candidates_.size();
  if (result.valid_depth_pixels == 0) {
    result.status = SelectionStatus::kNoValidDepth;
    return result;
  }

  const double target = static_cast<double>(std::max<std::size_t>(parameters_.target_points, 1));
  int s = std::max(1, static_cast<int>(std::lround(std::sqrt(static_cast<double>(candidates_.size()) / target))));
  std::size_t count = count_for_cell_size(s);
  int best_s = s;
  double best_error = std::abs(std::log(std::max<double>(static_cast<double>(count), 1.0) / target));
  for (int pass = 0; pass < 4 && count > 0; ++pass) {
    const double ratio = static_cast<double>(count) / target;
    if (ratio > 0.85 && ratio < 1.15) break;
    int next = std::clamp(static_cast<int>(std::lround(s * std::sqrt(ratio))), 1, kMaxCellSize);
    if (next == s) next = std::clamp(ratio > 1 ? s + 1 : s - 1, 1, kMaxCellSize);  // rounding stalled
    if (next == s) break;
    s = next;
    count = count_for_cell_size(s);
    const double error = std::abs(std::log(std::max<double>(static_cast<double>(count), 1.0) / target));
    if (error < best_error) {
      best_error = error;
      best_s = s;
    }
  }
  if (s != best_s) {  // the passes overshot: go back to the closest cell size
    s = best_s;
    count_for_cell_size(s);
  }
  result.cell_size = s;

  // 4. Back-project the winners, in row-major order of their cells (deterministic).
  const bool distorted = K.has_distortion();
  if (distorted && (rays_.empty() || !same_rays(K, ray_intrinsics_))) build_ray_table(K);
  const int cells = ((width_ + s - 1) / s) * ((height_ + s - 1) / s);
  const float fx_inv = static_cast<float>(1.0 / K.fx), fy_inv = static_cast<float>(1.0 / K.fy);
  const float cx = static_cast<float>(K.cx), cy = static_cast<float>(K.cy);
  const float depth_inv = static_cast<float>(1.0 / K.depth_scale);
  const auto gradient_weight = static_cast<float>(parameters_.gradient_weight);
  // Depth-time compensation (see the header).
  const bool compensate = colour_T_depth.angle() > 0 || colour_T_depth.translation().squaredNorm() > 0;
  const Eigen::Matrix3f R_cd = colour_T_depth.rotation_matrix().cast<float>();
  const Eigen::Matrix3f R_dc = R_cd.transpose();
  const Eigen::Vector3f t_cd = colour_T_depth.translation().cast<float>();
  const float fx = static_cast<float>(K.fx), fy = static_cast<float>(K.fy);
  const RollingShutter shutter(K, twist);
  for (int c = 0; c < cells; ++c) {
    const auto best = cell_best_[static_cast<std::size_t>(c)];
    if (best < 0) continue;
    const auto p = candidates_[static_cast<std::size_t>(best)];
    const int u = static_cast<int>(p % static_cast<std::uint32_t>(width_));
    const int v = static_cast<int>(p / static_cast<std::uint32_t>(width_));
    const float z = static_cast<float>(frame.depth.at<std::uint16_t>(v, u)) * depth_inv;
    const auto* px = frame.bgr.ptr<std::uint8_t>(v) + 3 * u;
    const Feature f{px[2] / 255.0f, px[1] / 255.0f, px[0] / 255.0f, gradient_weight * (grey_[p + 1] - grey_[p - 1]),
                    gradient_weight * (grey_[p + W] - grey_[p - W])};
    const float rx = distorted ? rays_[2 * p] : (static_cast<float>(u) - cx) * fx_inv;
    const float ry = distorted ? rays_[2 * p + 1] : (static_cast<float>(v) - cy) * fy_inv;
    if (!compensate) {
      cloud.push_back(shutter.at_frame_time(Eigen::Vector3f(rx * z, ry * z, z), v), f);
      continue;
    }
    // The ray at the depth time, projected through the lens into the depth image (registered to
    // the colour image, so the same distortion); its depth there scales that ray.
    const Eigen::Vector3f P_d = R_dc * (Eigen::Vector3f(rx * z, ry * z, z) - t_cd);
    if (!(P_d.z() > 0)) continue;
    const float x = P_d.x() / P_d.z(), y = P_d.y() / P_d.z();
    const auto [xd, yd] = distorted ? core::distort(K.distortion, x, y) : std::array<float, 2>{x, y};
    const auto ud = std::lround(fx * xd + cx), vd = std::lround(fy * yd + cy);
    if (ud < 0 || vd < 0 || ud >= width_ || vd >= height_) continue;
    const auto raw = static_cast<float>(frame.depth.at<std::uint16_t>(static_cast<int>(vd), static_cast<int>(ud)));
    if (raw <= 0 || raw < min_raw || raw > max_raw) continue;
    const Eigen::Vector3f P_c = R_cd * (P_d * (raw * depth_inv / P_d.z())) + t_cd;
    cloud.push_back(shutter.at_frame_time(P_c, v), f);
  }
  result.selected = cloud.size();
  if (cloud.overflowed() > 0) result.status = SelectionStatus::kCapacityClamped;
  return result;
}

}  // namespace cvo::registration
