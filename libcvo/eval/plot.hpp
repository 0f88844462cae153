#pragma once
// The evaluation figure, drawn with OpenCV only (cv::line, cv::putText, cv::imwrite):
//   left panel:  top view (x horizontal, y vertical, equal scale on both axes) as evaluate_ate.py
//                plots it: ground truth black, the estimate after the ATE alignment blue, and a
//                red segment joining each associated pair (its length is that pair's ATE error);
//                lines break where consecutive poses are more than 2 median intervals apart;
//   right panel: the translational ATE error of each pair over time, with its RMSE;
//   title:       the ATE RMSE and the number of pairs.
#include <filesystem>
#include <string>

#include <opencv2/core.hpp>

#include "libcvo/core/trajectory.hpp"
#include "libcvo/eval/ate.hpp"

namespace cvo::eval {

struct PlotOptions {
  cv::Size size{1200, 600};  // pixels; at least 400 x 300
  std::string title = {};    // shown before the ATE figures, e.g. the estimate's file name
};

/// A CV_8UC3 image of options.size. `ate` must come from these two trajectories.
/// Throws std::invalid_argument when the size is too small.
cv::Mat render_evaluation_plot(const core::Trajectory& groundtruth, const core::Trajectory& estimate,
                               const AteResult& ate, const PlotOptions& options = {});

/// Renders and writes a PNG; throws io::InputError naming the file when it cannot be written.
void write_evaluation_plot(const std::filesystem::path& png, const core::Trajectory& groundtruth,
                           const core::Trajectory& estimate, const AteResult& ate, const PlotOptions& options = {});

}  // namespace cvo::eval
