#pragma once
// Semi-dense point selection in the manner of DSO (Engel et al., "Direct Sparse Odometry", 2018),
// as the paper uses it to turn an RGB-D frame into about 3000 coloured points.
//
//  1. grey = (0.299 R + 0.587 G + 0.114 B) / 255; gradient g by central differences.
//  2. The image is cut into 32x32 regions; each region's threshold is the median of |g| there
//     plus a constant (DSO: median + 7 on the 0-255 scale), smoothed over the 3x3 neighbouring
//     regions, so that weak texture in a dull region still counts while strong texture in a busy
//     region is thinned.
//  3. Candidates are pixels above their region's threshold with valid depth in
//     [min_depth, max_depth]. The image is tiled by s x s cells and each cell keeps its strongest
//     candidate; s is adapted (a few passes) so about `target_points` survive, spreading points
//     over the whole image.
//     A frame with fewer candidates than target_points (a texture-less scene, whose real camera
//     noise, under a level at the pixel scale, passes no threshold of median + 7) is searched again
//     with each region's threshold at its median alone: about half of every region's pixels then
//     qualify and the cells spread target_points over the surfaces, whose geometry is all that can
//     register such a scene. DSO too lowers its thresholds when too few points pass. A textured
//     frame never comes here, so its selection is unchanged.
//  4. Each point is back-projected with the intrinsics and labelled with its RGB and gradient:
//     X = z · (x', y', 1) with z = raw_depth / depth_scale, raw_depth the mean of the valid depths
//     of the (2r+1)² pixels around it within a fraction of its own (its surface;
//     SelectionParameters::depth_window says why). Without lens distortion the ray is
//     x' = (u - cx) / fx, y' = (v - cy) / fy. With distortion (core::Intrinsics::distortion) it
//     is the undistorted ray of pixel (u, v), read from a per-pixel table that cv::undistortPoints
//     fills once per intrinsics. This assumes, as for TUM fr1/fr2, that depth is registered in the
//     same distorted colour image and holds z along the optical axis (not the range |X|), so the
//     depth needs no correction of its own.
//
// Deterministic, and after construction select() performs no heap allocation, except on the
// first frame of a distorted camera (or when its intrinsics change), which builds the ray table.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "libcvo/core/camera.hpp"
#include "libcvo/core/parameters.hpp"
#include "libcvo/core/rgbd_frame.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/registration/point_cloud.hpp"

namespace cvo::registration {

enum class SelectionStatus {
  kOk,
  kEmptyFrame,      // no image, or sizes differ from the selector's
  kBadImageType,    // colour not CV_8UC3 or depth not CV_16UC1
  kNoValidDepth,    // no pixel had usable depth: the cloud is empty
  kCapacityClamped  // more points qualified than the cloud holds; the rest were dropped
};
const char* to_string(SelectionStatus status);

struct SelectionResult {
  SelectionStatus status = SelectionStatus::kOk;
  std::size_t valid_depth_pixels = 0;
  std::size_t candidates = 0;  // above threshold with valid depth
  std::size_t selected = 0;
  int cell_size = 1;       // the s finally used
  bool at_median = false;  // too few candidates at median + 7: thresholds at the region medians (step 3)
};

// Raw depths lo <= d <= hi are valid (point_selection.cpp: valid_raw_depths).
struct RawDepthRange {
  std::uint16_t lo, hi;
};

class PointSelector {
 public:
  PointSelector(int width, int height, const core::SelectionParameters& parameters);

  /// Fills `cloud` (cleared first) with the selected points of `frame` in its camera frame.
  ///
  /// `colour_T_depth`: the camera at the depth image's time in its frame at the colour image's time
  /// (identity: simultaneous images). Otherwise each point's depth is read where its colour pixel's
  /// ray was at the depth time, P_d = R^T (P_c - t) with the pixel's own depth as the guess for the
  /// small translation, and the point is moved back to the colour time, P_c = R P_d + t, keeping the
  /// colour pixel's ray. Selected points are colour edges, often at depth discontinuities, where a
  /// few pixels of rotation between the two images read the other side's depth. A point whose
  /// compensated depth is missing or out of range is dropped.
  ///
  /// `twist`: the camera's motion per second in its own frame, [v; ω] (SE3::log order), for a
  /// rolling-shutter camera (frame.intrinsics.readout_s > 0; ignored otherwise). Row v was seen at
  /// τ = readout_s (v / (height - 1) - 1/2) from the frame's time (camera.hpp), by the camera
  /// exp(τ ξ) in the frame's camera; so each point is moved to the frame's time,
  ///   P <- P + τ (ω × P + v),
  /// to first order in τ ω (below 0.03 rad for 0.02 s at 90 °/s). Without it a camera pitching at ω
  /// sees its image stretched by ω · readout_s, a rotation error that does not cancel between frames
  /// turning at different rates.
  SelectionResult select(const core::RgbdFrame& frame, PointCloud& cloud, const core::SE3& colour_T_depth = core::SE3(),
                         const core::Vector6d& twist = core::Vector6d::Zero());

  /// `frame`, the one the last select() was given, selected again at another compensation: steps
  /// 1-3 depend on its images alone, so its winners are back-projected anew (step 4), the very
  /// points select() would give at that compensation, at a fraction of the cost. Any other frame
  /// (another index, stamp or image buffer) is selected in full.
  SelectionResult reselect(const core::RgbdFrame& frame, PointCloud& cloud, const core::SE3& colour_T_depth,
                           const core::Vector6d& twist = core::Vector6d::Zero());

  [[nodiscard]] int width() const { return width_; }
  [[nodiscard]] int height() const { return height_; }

 private:
  void thresholds_and_candidates(const core::RgbdFrame& frame, RawDepthRange valid, SelectionResult& result);
  void grey_row(const std::uint8_t* bgr, float* grey) const;
  void gradient_rows(int v0, int v1);
  void region_bins(int ry);
  [[nodiscard]] int count_at_most(int rx, int rows, int bin) const;
  void region_medians(int ry);
  void smooth_thresholds(int ry);
  void find_candidates(const cv::Mat& depth, int ry, RawDepthRange valid, SelectionResult& result);
  void candidates_at_median(const cv::Mat& depth, RawDepthRange valid, SelectionResult& result);
  void pack_row_flags(int v);
  int choose_cell_size(std::size_t candidates);
  std::size_t count_for_cell_size(int s);
  void choose_winners(int s);
  void build_ray_table(const core::Intrinsics& intrinsics);
  [[nodiscard]] RawDepthRange valid_depths(const core::Intrinsics& K) const;
  // What back_project() needs of a winner that depends on its images alone.
  struct Winner {
    int v = 0;             // its row (the rolling shutter's time)
    Feature label{};       // colour and gradient
    float rx = 0, ry = 0;  // undistorted ray (x/z, y/z)
    float depth = 0;       // raw depth over its window (0: none)
  };
  [[nodiscard]] Winner read_winner(const core::RgbdFrame& frame, std::size_t pixel, RawDepthRange valid,
                                   bool distorted) const;
  // `again` (reselect()): the winners kept by select() are used, when all of them fit.
  void back_project(const core::RgbdFrame& frame, PointCloud& cloud, const core::SE3& colour_T_depth,
                    const core::Vector6d& twist, SelectionResult& result, bool again);

  // The frame the last select() chose winners for (reselect()); no result: none.
  struct LastSelection {
    const void* bgr = nullptr;
    const void* depth = nullptr;
    std::uint64_t index = 0;
    double timestamp = 0;
    std::optional<SelectionResult> result;
  };
  LastSelection last_;

  int width_, height_;
  core::SelectionParameters parameters_;
  int regions_x_, regions_y_;
  int words_per_row_;                      // 64-pixel words of a row of candidate_bits_
  std::array<float, 3 * 256> grey_lut_{};  // B, G, R contributions to grey
  std::vector<float> grey_, magnitude_;
  std::vector<float> region_threshold_, smoothed_threshold_;  // the medians; smoothed, plus threshold_offset_
  float threshold_offset_ = 0;                                // DSO's constant above the median, or 0
  std::vector<std::uint8_t> bins_;  // step 2: the histogram bin of each pixel of one row of regions
  // Step 3: per image row, each pixel's threshold and its candidate flag (0/1, padded to whole
  // words); candidate_bits_: the flags of every row packed 64 to a word, bit u % 64 of word u / 64.
  std::vector<float> row_threshold_;
  std::vector<std::uint8_t> row_flags_;
  std::vector<std::uint64_t> candidate_bits_;
  std::vector<std::uint64_t> band_;        // the OR of the rows of one band of cells
  std::vector<std::int32_t> column_cell_;  // per column: its cell's (winners) or the next cell's first column (counts)
  std::vector<std::int32_t> cell_best_;    // per cell: pixel index of its strongest candidate or -1
  std::vector<float> cell_magnitude_;      // per cell: that candidate's |g|
  std::vector<Winner> winners_;            // select()'s winners, in order (fixed capacity)
  bool winners_kept_ = false;              // all of the last select()'s winners are in winners_
  // Distorted cameras only: undistorted (x/z, y/z) per pixel, row-major, for ray_intrinsics_.
  std::vector<float> rays_;
  core::Intrinsics ray_intrinsics_{};
};

}  // namespace cvo::registration
