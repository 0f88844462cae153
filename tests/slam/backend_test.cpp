#include "libcvo/slam/backend.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "tests/slam/synthetic_run.hpp"

namespace cvo::slam {
namespace {

using testing::loop;
using testing::make_run;
using testing::pose_xy_yaw;
using testing::position_error;
using testing::square;
using testing::SyntheticRun;

// Drift of the synthetic tracker: 0.06°/frame of yaw and 1 mm/frame forward; over the 40 frames
// of the square the end misses the start by ~4 cm and 2.4°.
const core::Vector6d kBias = (core::Vector6d() << 0.001, 0, 0, 0, 0, 0.001).finished();
constexpr double kInformation = 1e4;  // CVO-Hessian scale of every edge (σ ~ 1 cm, 0.6°)

void add_all(Backend& backend, const SyntheticRun& run) {
  for (const auto& g : run.graphs) backend.add_local_graph(static_cast<posegraph::NodeId>(g.keyframe().frame_index), g);
}

double rms_position_error(const core::Trajectory& estimate, const SyntheticRun& run) {
  double sum = 0;
  for (const auto& p : estimate)
    sum += std::pow(position_error(run.truth[static_cast<std::size_t>(p.timestamp)], p.pose), 2);
  return std::sqrt(sum / static_cast<double>(estimate.size()));
}

TEST(Backend, LocalGraphsChainTheKeyframesAsTheTrackerDid) {
  const SyntheticRun run = make_run(square(), 5, kBias, kInformation);
  Backend backend;
  add_all(backend, run);
  EXPECT_EQ(backend.local_graphs(), 8u);
  // Keyframes 0, 5, ..., 40, each joined to the next by one edge; the first fixed.
  EXPECT_EQ(backend.keyframe_graph().nodes().size(), 9u);
  EXPECT_EQ(backend.keyframe_graph().edges().size(), 8u);
  EXPECT_TRUE(backend.keyframe_graph().node(0).fixed);
  // Frames are where the tracker put them, every frame once, in order (within 3 mm: the biased
  // keyframe and chain measurements disagree slightly, and the local optimisation averages them).
  const core::Trajectory t = backend.frame_trajectory();
  ASSERT_EQ(t.size(), 41u);
  for (std::size_t n = 0; n < t.size(); ++n) {
    EXPECT_EQ(t[n].timestamp, static_cast<double>(n));
    EXPECT_LT(position_error(run.odometry[n], t[n].pose), 3e-3) << n;
  }
  EXPECT_GT(position_error(run.truth[40], t[40].pose), 0.03);  // the drift the loop must remove
  EXPECT_EQ(backend.revision(), 8u);
}

TEST(Backend, OneLoopCorrectsTheDriftOfASquare) {
  const SyntheticRun run = make_run(square(), 5, kBias, kInformation);
  Backend backend;
  add_all(backend, run);
  const double drift_end = position_error(run.truth[40], backend.keyframe_poses().at(40));
  const double drift_rms = rms_position_error(backend.frame_trajectory(), run);

  EXPECT_TRUE(backend.add_loop(loop(run, 0, 40, kInformation)));
  EXPECT_EQ(backend.unoptimised_loops(), 1u);
  const auto report = backend.optimise_keyframes();
  EXPECT_TRUE(report.converged) << report.stop_reason;
  EXPECT_EQ(backend.unoptimised_loops(), 0u);
  const double end = position_error(run.truth[40], backend.keyframe_poses().at(40));
  const double rms = rms_position_error(backend.frame_trajectory(), run);
  const auto loops = backend.loops();
  ASSERT_EQ(loops.size(), 1u);
  std::printf("square: end error %.4f -> %.4f m, frame RMS %.4f -> %.4f m, loop chi2 %.2f weight %.3f\n", drift_end,
              end, drift_rms, rms, loops[0].chi2, loops[0].weight);
  EXPECT_LT(end, 0.2 * drift_end);
  EXPECT_LT(rms, 0.5 * drift_rms);
  EXPECT_GT(loops[0].weight, 0.5);  // a consistent loop keeps most of its weight

  // The global optimisation of every frame keeps the correction (a little less of it: every frame's
  // chain edges make the odometry stiffer against the loop than the keyframe edges alone), and is
  // what frame_trajectory returns afterwards.
  const auto before = backend.revision();
  const auto all = backend.optimise_all();
  EXPECT_TRUE(all.converged) << all.stop_reason;
  EXPECT_GT(backend.revision(), before);
  const double rms_all = rms_position_error(backend.frame_trajectory(), run);
  const double end_all = position_error(run.truth[40], backend.keyframe_poses().at(40));
  std::printf("square: after optimise_all end error %.4f m, frame RMS %.4f m\n", end_all, rms_all);
  EXPECT_LT(rms_all, 0.5 * drift_rms);
  EXPECT_LT(end_all, 0.2 * drift_end);
  EXPECT_EQ(backend.keyframe_graph().node(0).pose.translation().norm(), 0.0);  // still fixed
}

// A wrong loop (keyframes 10 and 30, on opposite sides of the square, "measured" as 0.3 m apart)
// next to the right one: the Cauchy kernel leaves it almost no weight and the map stays as good as
// with the right loop alone.
TEST(Backend, AWrongLoopIsDownWeightedByTheKernel) {
  const SyntheticRun run = make_run(square(), 5, kBias, kInformation);
  Backend right_only, with_wrong;
  add_all(right_only, run);
  add_all(with_wrong, run);
  right_only.add_loop(loop(run, 0, 40, kInformation));
  with_wrong.add_loop(loop(run, 0, 40, kInformation));
  auto wrong = loop(run, 10, 30, kInformation);
  wrong.measurement = core::SE3::from_translation({0.3, 0, 0});
  EXPECT_GT(position_error(run.truth[10].inverse() * run.truth[30], wrong.measurement), 2.0);
  with_wrong.add_loop(wrong);
  right_only.optimise_keyframes();
  with_wrong.optimise_keyframes();

  const auto loops = with_wrong.loops();
  ASSERT_EQ(loops.size(), 2u);
  std::printf("wrong loop: chi2 %.0f weight %.2e; right loop weight %.3f\n", loops[1].chi2, loops[1].weight,
              loops[0].weight);
  EXPECT_LT(loops[1].weight, 1e-3);
  EXPECT_GT(loops[0].weight, 0.5);
  const double rms_right = rms_position_error(right_only.frame_trajectory(), run);
  const double rms_wrong = rms_position_error(with_wrong.frame_trajectory(), run);
  std::printf("wrong loop: frame RMS %.4f m (right loop alone %.4f m)\n", rms_wrong, rms_right);
  EXPECT_LT(rms_wrong, rms_right + 0.005);

  // The same wrong edge without the kernel would have pulled the two sides together.
  posegraph::PoseGraph plain = with_wrong.keyframe_graph();
  posegraph::PoseGraph naive;
  for (const auto& [id, node] : plain.nodes()) naive.add_node(id, node.pose, node.fixed);
  for (auto e : plain.edges()) {
    e.robust = false;
    naive.add_edge(e);
  }
  posegraph::optimize(naive);
  EXPECT_LT((naive.node(10).pose.translation() - naive.node(30).pose.translation()).norm(), 1.5);
}

// A tracking restart: the second graph's keyframe is not the first graph's last frame. A bridge
// keeps the graph connected; a loop to the restart keyframe waits until its graph arrives.
TEST(Backend, ARestartIsBridgedAndItsLoopWaits) {
  const SyntheticRun run = make_run(square(), 5, kBias, kInformation);
  // Graph 0..5 closes, frame 6 is lost, frame 7 restarts with a keyframe.
  odometry::LocalGraph first(5), second(6);
  for (const auto& n : run.graphs[0].nodes())
    if (n.frame_index <= 4) first.add_node(n);
  for (const auto& e : run.graphs[0].edges())
    if (e.to <= 4) first.add_edge(e);
  second.add_node({7, 7.0, run.odometry[7]});
  for (std::size_t n = 8; n <= 10; ++n) {
    const core::SE3 m = run.truth[7].inverse() * run.truth[n];
    second.add_node({n, static_cast<double>(n), run.odometry[7] * m});
    second.add_edge({7, n, m, kInformation * core::Matrix6d::Identity()});
  }

  Backend backend;
  backend.add_local_graph(0, first);
  EXPECT_FALSE(backend.add_loop(loop(run, 0, 7, kInformation)));  // keyframe 7 is not there yet
  EXPECT_EQ(backend.pending_loops(), 1u);
  backend.add_local_graph(7, second);
  EXPECT_EQ(backend.pending_loops(), 0u);
  EXPECT_EQ(backend.loops().size(), 1u);
  EXPECT_EQ(backend.unoptimised_loops(), 1u);
  // Nodes 0, 4 (the first graph's end, no keyframe), 7 and 10; edges 0→4, bridge 4→7, 7→10, loop.
  EXPECT_EQ(backend.keyframe_graph().nodes().size(), 4u);
  EXPECT_EQ(backend.keyframe_graph().edges().size(), 4u);
  EXPECT_LT(position_error(run.odometry[7], backend.keyframe_poses().at(7)), 1e-3);
  backend.optimise_keyframes();
  // The loop, far stronger than the bridge, places the restart keyframe at the truth.
  EXPECT_LT(position_error(run.truth[7], backend.keyframe_poses().at(7)), 1e-3);
  const core::Trajectory t = backend.frame_trajectory();
  EXPECT_EQ(t.size(), 9u);  // frames 0-4 and 7-10; frames 5 and 6 are in no graph
  backend.optimise_all();
  EXPECT_LT(position_error(run.truth[7], backend.keyframe_poses().at(7)), 1e-3);
}

// A session's graphs: the run's, renumbered from `first_node` and seen from another odometry frame
// (its tracker started elsewhere): poses G · P, relative measurements unchanged.
std::vector<odometry::LocalGraph> as_session(const SyntheticRun& run, std::uint64_t first_node, const core::SE3& G) {
  std::vector<odometry::LocalGraph> graphs;
  for (const auto& g : run.graphs) {
    odometry::LocalGraph out(g.nodes().size());
    for (auto n : g.nodes()) {
      n.frame_index += first_node;
      n.pose = G * n.pose;
      out.add_node(n);
    }
    for (auto e : g.edges()) {
      e.from += first_node;
      e.to += first_node;
      out.add_edge(e);
    }
    graphs.push_back(out);
  }
  return graphs;
}

void add_session(Backend& backend, core::SessionId session, const std::vector<odometry::LocalGraph>& graphs) {
  for (const auto& g : graphs)
    backend.add_local_graph(session, static_cast<posegraph::NodeId>(g.keyframe().frame_index), g);
}

TEST(Backend, ASessionStaysInItsOwnFrameUntilALoopJoinsItToTheMap) {
  const SyntheticRun run = make_run(square(), 5, kBias, kInformation);
  const core::SE3 elsewhere = pose_xy_yaw(5.0, -3.0, 1.2);
  Backend backend;
  add_session(backend, 11, as_session(run, 0, core::SE3()));
  add_session(backend, 22, as_session(run, 1000, elsewhere));
  add_session(backend, 33, as_session(run, 2000, pose_xy_yaw(-7.0, 2.0, -0.4)));

  // Unplaced: anchored where its own tracker put it, no correction, a piece of its own.
  EXPECT_TRUE(backend.placed(11));
  EXPECT_FALSE(backend.placed(22));
  EXPECT_EQ(backend.piece(22), 22);
  EXPECT_TRUE(backend.keyframe_graph().node(1000).fixed);
  EXPECT_LT(position_error(elsewhere * run.odometry[10], backend.keyframe_poses().at(1010)), 1e-3);
  // (no correction but the local optimisation's millimetres, the same as the first session's)
  EXPECT_LT(backend.odometry_correction(22).translation().norm(), 1e-2);
  backend.optimise_keyframes();  // three pieces, each held at its anchor: well-posed

  // Session 22 revisits session 11's frame 10 at its own frame 10: the same place.
  loop_closure::LoopClosure l = loop(run, 10, 10, kInformation);
  l.to = 1010;
  EXPECT_TRUE(backend.add_loop(l));
  EXPECT_TRUE(backend.placed(22));
  EXPECT_EQ(backend.piece(22), 11);
  EXPECT_FALSE(backend.keyframe_graph().node(1000).fixed);
  EXPECT_TRUE(backend.keyframe_graph().node(0).fixed);
  // Moved rigidly onto the loop: the two runs of one trajectory now coincide, and the correction
  // maps session 22's odometry into the map.
  for (std::size_t n = 0; n <= 40; n += 5)
    EXPECT_LT(position_error(backend.keyframe_poses().at(static_cast<std::int64_t>(n)),
                             backend.keyframe_poses().at(static_cast<std::int64_t>(1000 + n))),
              1e-6)
        << n;
  EXPECT_LT(position_error(backend.odometry_correction(11) * elsewhere.inverse(), backend.odometry_correction(22)),
            1e-6);
  EXPECT_TRUE(backend.optimise_keyframes().converged);
  EXPECT_LT(position_error(backend.keyframe_poses().at(20), backend.keyframe_poses().at(1020)), 1e-3);

  // Session 33 never met the others: still its own piece after every optimisation.
  EXPECT_FALSE(backend.placed(33));
  EXPECT_TRUE(backend.keyframe_graph().node(2000).fixed);
  EXPECT_TRUE(backend.optimise_all().converged);
  EXPECT_FALSE(backend.placed(33));
  EXPECT_EQ(backend.frame_trajectory(22).size(), 41u);
  EXPECT_EQ(backend.frame_trajectory().size(), 3 * 41u);
}

TEST(Backend, TwoUnplacedSessionsThatShareALoopBecomeOnePieceOutsideTheMap) {
  const SyntheticRun run = make_run(square(), 5, kBias, kInformation);
  Backend backend;
  add_session(backend, 1, as_session(run, 0, core::SE3()));
  add_session(backend, 2, as_session(run, 1000, pose_xy_yaw(1.0, 1.0, 0.5)));
  add_session(backend, 3, as_session(run, 2000, pose_xy_yaw(-2.0, 0.0, -0.5)));
  loop_closure::LoopClosure l = loop(run, 15, 15, kInformation);
  l.from = 1015;
  l.to = 2015;
  backend.add_loop(l);
  EXPECT_EQ(backend.piece(3), 2);  // the later session joins the earlier one's frame
  EXPECT_FALSE(backend.placed(2));
  EXPECT_FALSE(backend.placed(3));
  EXPECT_LT(position_error(backend.keyframe_poses().at(1015), backend.keyframe_poses().at(2015)), 1e-6);
  // A loop from the map to either places both.
  l.from = 25;
  l.to = 2025;
  l.measurement = core::SE3();
  backend.add_loop(l);
  EXPECT_TRUE(backend.placed(2));
  EXPECT_TRUE(backend.placed(3));
  EXPECT_TRUE(backend.optimise_keyframes().converged);
  EXPECT_LT(position_error(backend.keyframe_poses().at(30), backend.keyframe_poses().at(1030)), 1e-3);
}

TEST(Backend, BadInputIsRefused) {
  const SyntheticRun run = make_run(square(), 5, kBias, kInformation);
  Backend backend;
  EXPECT_THROW(backend.add_local_graph(0, odometry::LocalGraph(3)), std::invalid_argument);
  EXPECT_THROW(backend.add_local_graph(1, run.graphs[0]), std::invalid_argument);  // it starts at 0
  backend.add_local_graph(0, run.graphs[0]);
  EXPECT_THROW(backend.add_local_graph(0, run.graphs[0]), std::invalid_argument);  // twice
  EXPECT_THROW(backend.add_loop(loop(run, 5, 5, 1.0)), std::invalid_argument);
  auto nan = loop(run, 0, 5, 1.0);
  nan.information(0, 0) = std::nan("");
  EXPECT_THROW(backend.add_loop(nan), std::invalid_argument);
  // Nothing to optimise is not an error.
  Backend empty;
  EXPECT_EQ(empty.optimise_keyframes().iterations, 0);
  EXPECT_EQ(empty.optimise_all().iterations, 0);
  EXPECT_TRUE(empty.frame_trajectory().empty());
  EXPECT_EQ(empty.odometry_correction().translation().norm(), 0.0);
}

// An information matrix that is not positive semi-definite would make the keyframe graph's cost
// unbounded below (core/information.hpp): the loop and the local graph are refused, naming
// the edge, and nothing of them enters the graphs.
TEST(Backend, IndefiniteInformationIsRefused) {
  const SyntheticRun run = make_run(square(), 5, kBias, kInformation);
  Backend backend;
  backend.add_local_graph(0, run.graphs[0]);
  auto indefinite = loop(run, 0, 5, kInformation);
  indefinite.information(0, 1) = indefinite.information(1, 0) = 1.2 * kInformation;  // eigenvalue -0.2 kInformation
  try {
    backend.add_loop(indefinite);
    FAIL() << "a loop with an indefinite information matrix was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("loop 0 -> 5: information is not positive semi-definite"), std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(backend.loops().empty());
  EXPECT_EQ(backend.pending_loops(), 0u);

  odometry::LocalGraph bad(run.graphs[1].nodes().size());
  for (const auto& n : run.graphs[1].nodes()) bad.add_node(n);
  for (auto e : run.graphs[1].edges()) {
    if (bad.edges().empty()) e.information(3, 4) = e.information(4, 3) = 2 * kInformation;  // eigenvalue -kInformation
    bad.add_edge(e);
  }
  const auto keyframe = static_cast<posegraph::NodeId>(bad.keyframe().frame_index);
  try {
    backend.add_local_graph(keyframe, bad);
    FAIL() << "a local graph with an indefinite information matrix was accepted";
  } catch (const std::invalid_argument& e) {
    const std::string edge = "local graph edge " + std::to_string(bad.edges()[0].from) + " -> " +
                             std::to_string(bad.edges()[0].to) + ": information is not positive semi-definite";
    EXPECT_NE(std::string(e.what()).find(edge), std::string::npos) << e.what();
  }
  EXPECT_EQ(backend.local_graphs(), 1u);
  backend.add_local_graph(keyframe, run.graphs[1]);  // the good graph of that keyframe is still welcome
  EXPECT_EQ(backend.local_graphs(), 2u);
  EXPECT_TRUE(backend.add_loop(loop(run, 0, 5, kInformation)));
}

}  // namespace
}  // namespace cvo::slam
