#include "localize.hpp"

#include <algorithm>
#include <string>
#include <utility>

#include "libcvo/config/mapper_parameters.hpp"
#include "libcvo/config/module_parameters.hpp"
#include "libcvo/core/session.hpp"
#include "libcvo/io/input_error.hpp"
#include "libcvo/odometry/keyframe_odometry.hpp"
#include "libcvo/slam/mapper.hpp"
#include "libcvo/store/replay.hpp"
#include "libcvo/store/store_records.hpp"

namespace cvo::tools {
namespace {

namespace fs = std::filesystem;
using core::LocalizationState;
using namespace store;

// Every intact record of the store into the mapper; what cannot be used is named and skipped.
void replay_store(const fs::path& file, slam::Mapper& mapper, std::ostream& problems) {
  const StoreSnapshot snapshot = read_store(file);
  if (!snapshot.scan.clean())
    problems << "warning: "
             << describe_damage(file, snapshot.scan, "as a record being written or a crash leaves it", "is left out")
             << "\n";
  MessageDoor door;
  for (const auto& record : snapshot.scan.records) {
    const auto replayed =
        replay(door, mapper, record.kind, snapshot.payload(record), StoreSnapshot::payload_bytes(record));
    if (!replayed.why.empty())
      problems << file.string() << ": record at byte " << record.at << ": " << replayed.why << "\n";
  }
  if (mapper.backend().local_graphs() == 0)
    throw io::InputError(file, "no map: no local graph of a keyframe could be replayed (" +
                                   std::to_string(snapshot.scan.records.size()) + " intact records)");
}

// The first session id above every stored one.
core::SessionId first_free_session(const slam::Mapper& mapper) {
  core::SessionId highest = 0;
  for (const auto& s : mapper.map().sessions) highest = std::max(highest, s.session);
  return highest + 1;
}

}  // namespace

struct Localizer::State {
  State(const config::Config& config, loop_closure::Vocabulary vocabulary)
      : mapper(std::move(vocabulary), config::mapper_parameters(config)),
        parameters(config::keyframe_odometry_parameters(config)),
        robot(config::robot_name(config.trackerd.robot)) {}

  slam::Mapper mapper;
  odometry::KeyframeOdometryParameters parameters;
  std::string robot;                                    // what cvo-trackerd would name (trackerd.robot)
  std::unique_ptr<odometry::KeyframeOdometry> tracker;  // made at the first frame: its size
  core::SessionId session = 0;
  bool localized = false;  // the current session was localized at some frame
  std::optional<double> first_timestamp;
  core::Trajectory trajectory;
  LocalizeReport report;

  void count(LocalizationState state, const core::RgbdFrame& frame, const core::SE3& odometry_pose) {
    if (state == LocalizationState::kLocalizing) ++report.frames_localizing;
    if (state != LocalizationState::kLocalized) return;
    ++report.frames_localized;
    if (!localized && report.localized_after_s) ++report.relocalizations;  // an earlier session was localized
    if (!report.localized_after_s) report.localized_after_s = frame.timestamp - *first_timestamp;
    localized = true;
    trajectory.push_back({frame.timestamp, mapper.session(session).correction * odometry_pose});
  }

  void new_session() {
    ++session;
    ++report.sessions;
    localized = false;
  }
};

Localizer::Localizer(const config::Config& config, loop_closure::Vocabulary vocabulary, const fs::path& map_store,
                     std::ostream& problems)
    : state_(std::make_unique<State>(config, std::move(vocabulary))) {
  replay_store(map_store, state_->mapper, problems);
  state_->mapper.finish();  // the map as cvo-map makes it
  state_->mapper.localize_only();
  state_->session = first_free_session(state_->mapper) - 1;
  state_->new_session();
}

Localizer::~Localizer() = default;

odometry::TrackResult Localizer::track(const core::RgbdFrame& frame) {
  State& s = *state_;
  if (!s.tracker)
    s.tracker =
        std::make_unique<odometry::KeyframeOdometry>(frame.intrinsics.width, frame.intrinsics.height, s.parameters);
  if (!s.first_timestamp) s.first_timestamp = frame.timestamp;
  const odometry::TrackStep step = s.tracker->track(frame);
  if (step.lost) {  // the kidnapped robot: this session ends, another starts
    ++s.report.frames_lost;
    // The graphs of keyframes the back end has go to it; a keyframe this broken frame made does not.
    const auto hand = [&](const odometry::HandedLocalGraph& g) {
      if (s.mapper.knows(s.session, g.keyframe_id)) s.mapper.add_local_graph(s.session, g.keyframe_id, *g.graph);
    };
    if (const auto& g = step.closed_graph) hand(*g);
    if (const auto open = s.tracker->finish()) hand(*open);
    s.mapper.mark_lost(s.session);
    s.tracker->reset();
    s.new_session();
    return step;
  }
  // The state as it stood when the frame was tracked: its own keyframe is seen after.
  s.count(s.mapper.session(s.session).state, frame, step.published_pose());
  if (const auto& g = step.closed_graph) s.mapper.add_local_graph(s.session, g->keyframe_id, *g->graph);
  if (const auto& k = step.new_keyframe)
    s.mapper.add_keyframe({s.session, k->id, k->frame, k->pose, *k->cloud, s.robot});
  s.report.window_keyframes_max = std::max(s.report.window_keyframes_max, s.mapper.window_keyframes());
  return step;
}

const core::Trajectory& Localizer::trajectory() const { return state_->trajectory; }
const LocalizeReport& Localizer::report() const { return state_->report; }

}  // namespace cvo::tools
