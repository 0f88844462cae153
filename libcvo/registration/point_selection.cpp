#include "libcvo/registration/point_selection.hpp"

#include <algorithm>
#include <array>
#include <bit>
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
        v_(twist.head<3>().cast<float>()),
        w_(twist.tail<3>().cast<float>()) {}

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

constexpr int kRegion = 32;                        // DSO's threshold region size (pixels)
constexpr int kHistogramBins = 50;                 // |g| on the 0-255 scale, clipped
constexpr float kThresholdOffset = 7.0f / 255.0f;  // DSO's constant above the median
constexpr int kMaxCellSize = 64;

// Bytes p[0..N) as a little-endian integer (one load where the machine is little-endian).
template <int N>
std::uint64_t little_endian(const std::uint8_t* p) {
  std::uint64_t x = 0;
  for (int i = 0; i < N; ++i) x |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  return x;
}

// The raw depths d that pass step 3's float test !(d <= 0 || d < min_raw || d > max_raw): an
// interval, each part of the test being monotone in d, found by bisection on that very test so
// that it holds for any bounds (NaN, infinite, fractional), while the per-pixel test becomes two
// 16-bit integer comparisons. Empty: {1, 0}.
RawDepthRange valid_raw_depths(float min_raw, float max_raw) {
  const auto above_min = [&](std::int32_t d) {
    const auto f = static_cast<float>(d);
    return !(f <= 0) && !(f < min_raw);
  };
  const auto below_max = [&](std::int32_t d) { return !(static_cast<float>(d) > max_raw); };
  std::int32_t lo = 0, hi = 65536;  // first d in [0, 65536) with above_min, 65536 if none
  while (lo < hi) {
    const std::int32_t mid = (lo + hi) / 2;
    if (above_min(mid))
      hi = mid;
    else
      lo = mid + 1;
  }
  std::int32_t first = lo;
  lo = -1, hi = 65535;  // last d in [0, 65536) with below_max, -1 if none
  while (lo < hi) {
    const std::int32_t mid = (lo + hi + 1) / 2;
    if (below_max(mid))
      lo = mid;
    else
      hi = mid - 1;
  }
  const std::int32_t last = lo;
  if (first > last) return {1, 0};
  return {static_cast<std::uint16_t>(first), static_cast<std::uint16_t>(last)};
}

// The raw depth at (u, v) averaged over its (2r+1)² window: the valid depths within
// `tolerance` · d of the pixel's own d (SelectionParameters::depth_window). 0 when d is not valid.
float window_depth(const cv::Mat& depth, int u, int v, int r, float tolerance, RawDepthRange valid) {
  const int centre = depth.at<std::uint16_t>(v, u);
  if (centre < valid.lo || centre > valid.hi) return 0;
  if (r <= 0) return static_cast<float>(centre);
  // The surface's depths [lo, hi]: within the band of the centre and valid (integers, no branch in
  // the loop: the window is read a few thousand times a frame).
  const int band = static_cast<int>(tolerance * static_cast<float>(centre));
  const int lo = std::max<int>(valid.lo, centre - band), hi = std::min<int>(valid.hi, centre + band);
  int sum = 0, n = 0;
  const int x0 = std::max(0, u - r), x1 = std::min(depth.cols - 1, u + r);
  for (int y = std::max(0, v - r); y <= std::min(depth.rows - 1, v + r); ++y) {
    const auto* row = depth.ptr<std::uint16_t>(y);
    for (int x = x0; x <= x1; ++x) {
      const int d = row[x];
      const int in = static_cast<int>(d >= lo) & static_cast<int>(d <= hi);
      sum += in * d;
      n += in;
    }
  }
  return static_cast<float>(sum) / static_cast<float>(n);  // n >= 1: the centre itself
}

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
    : width_(width),
      height_(height),
      parameters_(parameters),
      regions_x_((width + kRegion - 1) / kRegion),
      regions_y_((height + kRegion - 1) / kRegion),
      words_per_row_((width + 63) / 64) {
  const auto n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  const auto W = static_cast<std::size_t>(width), words = static_cast<std::size_t>(words_per_row_);
  grey_.resize(n);
  // Per-channel tables of w_c · value / 255: three loads and two adds per pixel instead of three
  // integer-to-float conversions and multiplies.
  constexpr std::array<float, 3> kWeights{0.114f, 0.587f, 0.299f};  // B, G, R (ITU-R 601)
  for (std::size_t c = 0; c < 3; ++c)
    for (std::size_t v = 0; v < 256; ++v) grey_lut_[256 * c + v] = kWeights[c] * static_cast<float>(v) / 255.0f;
  magnitude_.assign(n, 0.0f);  // borders stay zero: they are never candidates
  region_threshold_.resize(static_cast<std::size_t>(regions_x_ * regions_y_));
  smoothed_threshold_.resize(region_threshold_.size());
  bins_.resize(static_cast<std::size_t>(kRegion) * W);
  row_threshold_.resize(W);
  row_flags_.assign(64 * words, 0);  // the first pixel and the padding stay 0: never candidates
  candidate_bits_.resize(static_cast<std::size_t>(height) * words);
  band_.resize(words);
  column_cell_.resize(W);
  cell_best_.resize(n);  // enough for s = 1
  cell_magnitude_.resize(n);
  winners_.resize(n / 16);  // s >= 4 (VGA at ~3 000 points has s = 4-6); more are read again
}

void PointSelector::grey_row(const std::uint8_t* bgr, float* grey) const {
  // Bound by loads: three byte loads and three table loads a pixel. Four pixels' 12 bytes are read
  // as two words and split by shifts, leaving the table loads.
  const float* lut = grey_lut_.data();
  int u = 0;
  for (; u + 4 <= width_; u += 4, bgr += 12) {
    const std::uint64_t a = little_endian<8>(bgr);  // pixels u, u + 1 and two bytes of u + 2
    const std::uint64_t b = little_endian<4>(bgr + 8);
    const auto byte = [](std::uint64_t x, int k) { return static_cast<std::size_t>((x >> (8 * k)) & 0xff); };
    grey[u] = lut[byte(a, 0)] + lut[256 + byte(a, 1)] + lut[512 + byte(a, 2)];
    grey[u + 1] = lut[byte(a, 3)] + lut[256 + byte(a, 4)] + lut[512 + byte(a, 5)];
    grey[u + 2] = lut[byte(a, 6)] + lut[256 + byte(a, 7)] + lut[512 + byte(b, 0)];
    grey[u + 3] = lut[byte(b, 1)] + lut[256 + byte(b, 2)] + lut[512 + byte(b, 3)];
  }
  for (; u < width_; ++u, bgr += 3) grey[u] = lut[bgr[0]] + lut[256 + bgr[1]] + lut[512 + bgr[2]];
}

void PointSelector::gradient_rows(int v0, int v1) {
  // |g| of rows [v0, v1), interior pixels only: border pixels keep the zero magnitude set at
  // construction. gx, gy themselves are only needed for the selected points (step 4).
  const auto W = static_cast<std::size_t>(width_);
  for (int v = std::max(v0, 1); v < std::min(v1, height_ - 1); ++v) {
    const float* g = grey_.data() + static_cast<std::size_t>(v) * W;
    float* m = magnitude_.data() + static_cast<std::size_t>(v) * W;
    for (int u = 1; u + 1 < width_; ++u) {
      const float gx = g[u + 1] - g[u - 1];  // central difference x 2: range [-1, 1]
      const float gy = g[static_cast<std::ptrdiff_t>(u) + static_cast<std::ptrdiff_t>(W)] -
                       g[static_cast<std::ptrdiff_t>(u) - static_cast<std::ptrdiff_t>(W)];
      m[u] = 0.5f * std::sqrt(gx * gx + gy * gy);
    }
  }
}

void PointSelector::thresholds_and_candidates(const core::RgbdFrame& frame, RawDepthRange valid,
                                              SelectionResult& result) {
  // Steps 1-3 one row of regions at a time, so that each image row is read back while it is still
  // in cache: grey and |g| of region row ry (grey one row ahead for the vertical difference), its
  // thresholds, then the smoothed thresholds and candidates of row ry - 1, whose neighbours are
  // all known by then.
  const auto W = static_cast<std::size_t>(width_), words = static_cast<std::size_t>(words_per_row_);
  std::fill_n(candidate_bits_.begin(), words, 0);                                     // row 0
  std::fill_n(candidate_bits_.end() - static_cast<std::ptrdiff_t>(words), words, 0);  // last row
  int grey_done = 0;  // rows [0, grey_done) have their grey
  for (int ry = 0; ry <= regions_y_; ++ry) {
    if (ry < regions_y_) {
      const int v0 = ry * kRegion, v1 = std::min(height_, v0 + kRegion);
      for (; grey_done < std::min(height_, v1 + 1); ++grey_done)
        grey_row(frame.bgr.ptr<std::uint8_t>(grey_done), grey_.data() + static_cast<std::size_t>(grey_done) * W);
      gradient_rows(v0, v1);
      region_medians(ry);
    }
    if (ry > 0) {
      smooth_thresholds(ry - 1);
      find_candidates(frame.depth, ry - 1, valid, result);
    }
  }
}

void PointSelector::region_bins(int ry) {
  // The histogram bin of |g| (0-255 scale, clipped) of every pixel of region row ry, into bins_.
  // Local pointers: the byte stores could otherwise alias the members, which stops vectorisation.
  const int W = width_;
  for (int v = ry * kRegion; v < std::min(height_, (ry + 1) * kRegion); ++v) {
    const float* m = magnitude_.data() + static_cast<std::size_t>(v) * static_cast<std::size_t>(W);
    std::uint8_t* bins = bins_.data() + static_cast<std::size_t>((v - ry * kRegion) * W);
    for (int u = 0; u < W; ++u)
      bins[u] = static_cast<std::uint8_t>(std::min(kHistogramBins - 1, static_cast<int>(m[u] * 255.0f)));
  }
}

int PointSelector::count_at_most(int rx, int rows, int bin) const {
  // Pixels of region rx (of the row in bins_) whose bin is <= `bin`, counted in byte lanes (at
  // most kRegion each), a loop that vectorises, where a histogram increments one counter a pixel.
  const int u0 = rx * kRegion, n = std::min(width_, u0 + kRegion) - u0;
  const auto b = static_cast<std::uint8_t>(bin);
  std::array<std::uint8_t, kRegion> lanes{};
  for (int r = 0; r < rows; ++r) {
    const std::uint8_t* row = bins_.data() + static_cast<std::size_t>(r * width_ + u0);
    for (int k = 0; k < n; ++k)
      lanes[static_cast<std::size_t>(k)] =
          static_cast<std::uint8_t>(lanes[static_cast<std::size_t>(k)] + (row[k] <= b));
  }
  int count = 0;
  for (const auto lane : lanes) count += lane;
  return count;
}

void PointSelector::region_medians(int ry) {
  // Median |g| per region of row ry: the first bin b < kHistogramBins - 1 where at least
  // half the region's pixels have a bin <= b (else the last bin), found by bisection, as that
  // count grows with b.
  region_bins(ry);
  const int rows = std::min(height_, (ry + 1) * kRegion) - ry * kRegion;
  for (int rx = 0; rx < regions_x_; ++rx) {
    const int total = rows * (std::min(width_, (rx + 1) * kRegion) - rx * kRegion);
    int lo = 0, hi = kHistogramBins - 1;
    while (lo < hi) {
      const int mid = (lo + hi) / 2;
      if (2 * count_at_most(rx, rows, mid) >= total)
        hi = mid;
      else
        lo = mid + 1;
    }
    region_threshold_[static_cast<std::size_t>(ry * regions_x_ + rx)] = (static_cast<float>(lo) + 0.5f) / 255.0f;
  }
}

void PointSelector::smooth_thresholds(int ry) {
  // The medians of row ry averaged over each region's 3x3 neighbourhood (the regions that exist),
  // plus the offset (a constant commutes with the average).
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
    smoothed_threshold_[static_cast<std::size_t>(ry * regions_x_ + rx)] =
        sum / static_cast<float>(n) + threshold_offset_;
  }
}

void PointSelector::find_candidates(const cv::Mat& depth, int ry, RawDepthRange valid_range, SelectionResult& result) {
  // Candidates of region row ry: above their region's threshold with valid depth, interior pixels
  // only. Flags without branches (the loop vectorises; local pointers, as the byte stores could
  // alias the members), packed into candidate_bits_ row by row: later passes read only the bits.
  const int W = width_;
  std::uint8_t* flags = row_flags_.data();
  float* threshold = row_threshold_.data();
  const float* t = smoothed_threshold_.data() + static_cast<std::size_t>(ry * regions_x_);
  for (int u = 0; u < W; ++u) threshold[u] = t[u / kRegion];
  const std::uint16_t lo = valid_range.lo, hi = valid_range.hi;
  for (int v = std::max(1, ry * kRegion); v < std::min(height_ - 1, (ry + 1) * kRegion); ++v) {
    const auto* d_row = depth.ptr<std::uint16_t>(v);
    const float* m = magnitude_.data() + static_cast<std::size_t>(v) * static_cast<std::size_t>(W);
    std::uint16_t valid = 0, candidates = 0;  // per row (< 2^16 pixels): narrow lanes vectorise better
    for (int u = 1; u + 1 < W; ++u) {
      const bool ok = (d_row[u] >= lo) & (d_row[u] <= hi);
      const bool candidate = ok & (m[u] > threshold[u]);
      valid = static_cast<std::uint16_t>(valid + ok);
      candidates = static_cast<std::uint16_t>(candidates + candidate);
      flags[u] = static_cast<std::uint8_t>(candidate);
    }
    pack_row_flags(v);
    result.valid_depth_pixels += valid;
    result.candidates += candidates;
  }
}

// Step 3 again with every region's threshold at its (smoothed) median: the grey, |g| and medians
// of the first pass stand.
void PointSelector::candidates_at_median(const cv::Mat& depth, RawDepthRange valid, SelectionResult& result) {
  threshold_offset_ = 0;
  result.at_median = true;
  result.valid_depth_pixels = result.candidates = 0;
  for (int ry = 0; ry < regions_y_; ++ry) {
    smooth_thresholds(ry);
    find_candidates(depth, ry, valid, result);
  }
}

void PointSelector::pack_row_flags(int v) {
  // Eight 0/1 bytes b_i (little-endian in x) to the bits b_i << i: the product puts b_i at bit
  // 56 + i and every other term below bit 56 without carries, or above bit 63.
  std::uint64_t* bits = candidate_bits_.data() + static_cast<std::size_t>(v * words_per_row_);
  const std::uint8_t* f = row_flags_.data();
  for (std::size_t w = 0; w < static_cast<std::size_t>(words_per_row_); ++w) {
    std::uint64_t word = 0;
    for (std::size_t b = 0; b < 8; ++b, f += 8) {
      std::uint64_t x = 0;
      for (std::size_t i = 0; i < 8; ++i) x |= static_cast<std::uint64_t>(f[i]) << (8 * i);
      word |= ((x * 0x0102040810204080ull) >> 56) << (8 * b);
    }
    bits[w] = word;
  }
}

std::size_t PointSelector::count_for_cell_size(int s) {
  // The number of s x s cells holding a candidate (each will keep one). Per band of s rows, the OR
  // of the rows' bits; then from each set bit, one more cell, and the search goes on from the next
  // cell's first column: one step per occupied cell rather than a look at every cell.
  for (int u = 0, next = s; u < width_; ++u) {  // the next cell's first column, without divisions
    if (u == next) next += s;
    column_cell_[static_cast<std::size_t>(u)] = next;
  }
  const auto words = static_cast<std::size_t>(words_per_row_);
  std::uint64_t* band = band_.data();
  std::size_t count = 0;
  for (int y0 = 0; y0 < height_; y0 += s) {
    std::fill_n(band, words, 0);
    for (int v = y0; v < std::min(height_, y0 + s); ++v) {
      const std::uint64_t* row = candidate_bits_.data() + static_cast<std::size_t>(v) * words;
      for (std::size_t w = 0; w < words; ++w) band[w] |= row[w];
    }
    // Bits past the last column are 0 (row_flags_' padding), so every bit found is a pixel.
    std::size_t w = 0;
    std::uint64_t word = band[0];
    while (true) {
      while (word == 0 && ++w < words) word = band[w];
      if (word == 0) break;
      const auto u = 64 * w + static_cast<std::size_t>(std::countr_zero(word));
      ++count;
      const auto next = static_cast<std::size_t>(column_cell_[u]);
      if (next / 64 != w) {
        w = next / 64;
        if (w >= words) break;
        word = band[w];
      }
      word &= ~0ull << (next % 64);
    }
  }
  return count;
}

void PointSelector::choose_winners(int s) {
  // Keep the strongest candidate of every s x s cell in cell_best_. Candidates in row-major order
  // and a strict comparison keep the first of equals; without branches, as which one wins is
  // unpredictable. cell_magnitude_ starts below any candidate's |g| (> its threshold > 0).
  const int cells_x = (width_ + s - 1) / s;
  const int cells_y = (height_ + s - 1) / s;
  const auto cells = static_cast<std::size_t>(cells_x * cells_y);
  std::fill_n(cell_best_.begin(), cells, -1);
  std::fill_n(cell_magnitude_.begin(), cells, -1.0f);
  for (int u = 0, cell = 0, next = s; u < width_; ++u) {  // u / s without divisions
    if (u == next) ++cell, next += s;
    column_cell_[static_cast<std::size_t>(u)] = cell;
  }
  const auto W = static_cast<std::size_t>(width_), words = static_cast<std::size_t>(words_per_row_);
  const float* magnitude = magnitude_.data();
  const std::int32_t* column_cell = column_cell_.data();
  for (int v = 0; v < height_; ++v) {
    const auto first_cell = static_cast<std::size_t>((v / s) * cells_x);
    std::int32_t* best = cell_best_.data() + first_cell;
    float* best_magnitude = cell_magnitude_.data() + first_cell;
    const std::size_t row_start = static_cast<std::size_t>(v) * W;
    for (std::size_t w = 0; w < words; ++w) {
      for (std::uint64_t bits = candidate_bits_[static_cast<std::size_t>(v) * words + w]; bits != 0; bits &= bits - 1) {
        const std::size_t u = 64 * w + static_cast<std::size_t>(std::countr_zero(bits));
        const auto c = static_cast<std::size_t>(column_cell[u]);
        const float m = magnitude[row_start + u];
        const auto better = static_cast<std::int32_t>(m > best_magnitude[c]);
        best_magnitude[c] = std::max(best_magnitude[c], m);  // best_magnitude[c] < m ? m : best_magnitude[c]
        best[c] = (static_cast<std::int32_t>(row_start + u) & -better) | (best[c] & (better - 1));
      }
    }
  }
}

int PointSelector::choose_cell_size(std::size_t candidates) {
  // A few passes adapting s to bring the number of occupied cells near the target; the closest
  // cell size seen wins.
  const double target = static_cast<double>(std::max<std::size_t>(parameters_.target_points, 1));
  int s = std::max(1, static_cast<int>(std::lround(std::sqrt(static_cast<double>(candidates) / target))));
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
  return best_s;  // the passes may have overshot: go back to the closest cell size
}

void PointSelector::build_ray_table(const core::Intrinsics& K) {
  core::Intrinsics sized = K;
  sized.width = width_;
  sized.height = height_;
  rays_ = core::undistorted_pixel_rays(sized);
  ray_intrinsics_ = K;
}

// The raw depths in [min_depth_m, max_depth_m] of a camera's depth scale.
RawDepthRange PointSelector::valid_depths(const core::Intrinsics& K) const {
  return valid_raw_depths(static_cast<float>(parameters_.min_depth_m * K.depth_scale),
                          static_cast<float>(parameters_.max_depth_m * K.depth_scale));
}

SelectionResult PointSelector::select(const core::RgbdFrame& frame, PointCloud& cloud, const core::SE3& colour_T_depth,
                                      const core::Vector6d& twist) {
  cloud.clear();
  last_ = {};
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
  // 1-3: grey and |g|, the region thresholds, the candidates with valid depth.
  const RawDepthRange valid = valid_depths(frame.intrinsics);
  threshold_offset_ = kThresholdOffset;
  thresholds_and_candidates(frame, valid, result);
  if (result.candidates < parameters_.target_points && result.valid_depth_pixels > 0)
    candidates_at_median(frame.depth, valid, result);
  if (result.valid_depth_pixels == 0) {
    result.status = SelectionStatus::kNoValidDepth;
    return result;
  }
  const int s = choose_cell_size(result.candidates);
  choose_winners(s);
  result.cell_size = s;
  last_ = {frame.bgr.data, frame.depth.data, frame.index, frame.timestamp, result};
  back_project(frame, cloud, colour_T_depth, twist, result, false);
  return result;
}

SelectionResult PointSelector::reselect(const core::RgbdFrame& frame, PointCloud& cloud,
                                        const core::SE3& colour_T_depth, const core::Vector6d& twist) {
  if (!last_.result || frame.bgr.data != last_.bgr || frame.depth.data != last_.depth || frame.index != last_.index ||
      frame.timestamp != last_.timestamp)
    return select(frame, cloud, colour_T_depth, twist);
  cloud.clear();
  SelectionResult result = *last_.result;
  result.status = SelectionStatus::kOk;
  back_project(frame, cloud, colour_T_depth, twist, result, true);
  return result;
}

PointSelector::Winner PointSelector::read_winner(const core::RgbdFrame& frame, std::size_t p, RawDepthRange valid,
                                                 bool distorted) const {
  const auto& K = frame.intrinsics;
  const auto W = static_cast<std::size_t>(width_);
  const int u = static_cast<int>(p % W), v = static_cast<int>(p / W);
  const auto* px = frame.bgr.ptr<std::uint8_t>(v) + 3 * u;
  const auto gradient_weight = static_cast<float>(parameters_.gradient_weight);
  Winner w;
  w.v = v;
  w.label = {px[2] / 255.0f, px[1] / 255.0f, px[0] / 255.0f, gradient_weight * (grey_[p + 1] - grey_[p - 1]),
             gradient_weight * (grey_[p + W] - grey_[p - W])};
  w.rx = distorted ? rays_[2 * p] : (static_cast<float>(u) - static_cast<float>(K.cx)) * static_cast<float>(1.0 / K.fx);
  w.ry = distorted ? rays_[2 * p + 1]
                   : (static_cast<float>(v) - static_cast<float>(K.cy)) * static_cast<float>(1.0 / K.fy);
  w.depth = window_depth(frame.depth, u, v, parameters_.depth_window,
                         static_cast<float>(parameters_.depth_window_tolerance), valid);
  return w;
}

// 4. Back-project the winners, in row-major order of their cells (deterministic). What depends on
// the images alone (label, ray, own depth) is read once by select() and kept for reselect():
// winners lie a few pixels apart over the whole image, which has left the caches by then, and
// those reads were most of this step's time.
void PointSelector::back_project(const core::RgbdFrame& frame, PointCloud& cloud, const core::SE3& colour_T_depth,
                                 const core::Vector6d& twist, SelectionResult& result, bool again) {
  const auto& K = frame.intrinsics;
  const int s = result.cell_size;
  const RawDepthRange valid = valid_depths(K);
  const bool distorted = K.has_distortion();
  if (distorted && (rays_.empty() || !same_rays(K, ray_intrinsics_))) build_ray_table(K);
  const int cells = ((width_ + s - 1) / s) * ((height_ + s - 1) / s);
  const float cx = static_cast<float>(K.cx), cy = static_cast<float>(K.cy);
  const float depth_inv = static_cast<float>(1.0 / K.depth_scale);
  // Depth-time compensation (see the header).
  const bool compensate = colour_T_depth.angle() > 0 || colour_T_depth.translation().squaredNorm() > 0;
  const Eigen::Matrix3f R_cd = colour_T_depth.rotation_matrix().cast<float>();
  const Eigen::Matrix3f R_dc = R_cd.transpose();
  const Eigen::Vector3f t_cd = colour_T_depth.translation().cast<float>();
  const float fx = static_cast<float>(K.fx), fy = static_cast<float>(K.fy);
  const RollingShutter shutter(K, twist);
  const int window = parameters_.depth_window;
  const auto tolerance = static_cast<float>(parameters_.depth_window_tolerance);
  const bool kept = again && winners_kept_;
  std::size_t k = 0;  // the winner's rank
  for (int c = 0; c < cells; ++c) {
    const auto best = cell_best_[static_cast<std::size_t>(c)];
    if (best < 0) continue;
    const Winner w = kept ? winners_[k] : read_winner(frame, static_cast<std::size_t>(best), valid, distorted);
    if (!again && k < winners_.size()) winners_[k] = w;
    ++k;
    const float z = w.depth * depth_inv;
    if (!compensate) {
      cloud.push_back(shutter.at_frame_time(Eigen::Vector3f(w.rx * z, w.ry * z, z), w.v), w.label);
      continue;
    }
    // The ray at the depth time, projected through the lens into the depth image (registered to
    // the colour image, so the same distortion); its depth there scales that ray.
    const Eigen::Vector3f P_d = R_dc * (Eigen::Vector3f(w.rx * z, w.ry * z, z) - t_cd);
    if (!(P_d.z() > 0)) continue;
    const float x = P_d.x() / P_d.z(), y = P_d.y() / P_d.z();
    const auto [xd, yd] = distorted ? core::distort(K.distortion, x, y) : std::array<float, 2>{x, y};
    const auto ud = std::lround(fx * xd + cx), vd = std::lround(fy * yd + cy);
    if (ud < 0 || vd < 0 || ud >= width_ || vd >= height_) continue;
    const float raw = window_depth(frame.depth, static_cast<int>(ud), static_cast<int>(vd), window, tolerance, valid);
    if (!(raw > 0)) continue;
    const Eigen::Vector3f P_c = R_cd * (P_d * (raw * depth_inv / P_d.z())) + t_cd;
    cloud.push_back(shutter.at_frame_time(P_c, w.v), w.label);
  }
  if (!again) winners_kept_ = k <= winners_.size();
  result.selected = cloud.size();
  if (cloud.overflowed() > 0) result.status = SelectionStatus::kCapacityClamped;
}

}  // namespace cvo::registration
