#pragma once
// A session localized in a read-only map (Mapper::localize_only): where its odometry frame sits in
// the map, from the verified loops of its newest keyframes to the map's keyframes.
//
// The window is a small pose graph:
//   nodes   the session's window keyframes (free) and the map keyframes its loops reach (fixed:
//           the map is not changed by a visitor);
//   edges   between consecutive window keyframes, the tracker's keyframe→next-keyframe edge from
//           the earlier one's local graph (its CVO Hessian made the edge's information,
//           edge_information.hpp), or, before that graph came, the odometry difference with the
//           weak bridge information (core::PoseGraphParameters); every loop as a robust (Cauchy)
//           edge with its verification's information, as the back end weighs loops.
// Levenberg-Marquardt over it gives every window keyframe's map pose P_i; the correction is the
// newest keyframe's, T_map_odom = P_newest · O_newest⁻¹ (O its odometry pose): the frames since
// follow by their odometry, exactly as a tracker applies a CVO_MAP.
//
// Before the session is localized the first loop gives the initial poses (P_i = P_j · T_j^i,
// then the odometry); after, the current correction does. A window without loops (they have all
// left it) is not solved: the correction stays, carried by the odometry, and the covariance of the
// newest keyframe's map pose is the last solve's carried the same way by the caller.
//
// The covariance of the newest keyframe's map pose is the Laplace marginal of the solved window
// (posegraph::marginal_covariances), right-perturbed, [rho; phi].
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "libcvo/core/parameters.hpp"
#include "libcvo/core/se3.hpp"
#include "libcvo/loop_closure/loop_verification.hpp"
#include "libcvo/posegraph/pose_graph.hpp"

namespace cvo::slam {

struct WindowKeyframe {
  std::int64_t id = 0;         // in its session
  posegraph::NodeId node = 0;  // the mapper's node id (unique across sessions)
  double timestamp = 0;        // colour image time
  core::SE3 odometry;          // T_odom_keyframe
  // The edge to the next window keyframe, from this keyframe's local graph (node ids the mapper's).
  std::optional<posegraph::Edge> next;
};

/// A verified loop from a map keyframe (`loop.from`, fixed at `map_pose`) to a window keyframe.
struct WindowMatch {
  loop_closure::LoopClosure loop;
  core::SE3 map_pose;  // T_map_keyframe of loop.from
};

struct WindowSolution {
  core::SE3 correction;                      // T_map_odom at the newest window keyframe
  std::optional<core::Matrix6d> covariance;  // of the newest keyframe's map pose
  std::vector<double> loop_weights;          // Cauchy weight of each match at the solution, in order
};

/// Solves the window (see above); nullopt when there is no match or no keyframe. `correction`:
/// the session's current correction when it is localized already.
std::optional<WindowSolution> solve_window(const std::deque<WindowKeyframe>& window,
                                           const std::vector<WindowMatch>& matches,
                                           const std::optional<core::SE3>& correction,
                                           const core::PoseGraphParameters& parameters);

}  // namespace cvo::slam
