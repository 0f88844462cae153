#include "store_output.hpp"

#include <cmath>
#include <string>
#include <vector>

#include "libcvo/io/input_error.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/keyframe_conversion.hpp"
#include "libcvo/lcm/local_graph_conversion.hpp"
#include "libcvo/lcm/rgbd_conversion.hpp"
#include "libcvo/store/keyframe_store.hpp"
#include "libcvo/store/store_merges.hpp"

namespace cvo::tools {
namespace {

namespace fs = std::filesystem;
using store::Appended;
using store::KeyframeStore;
using store::RecordKind;

// The store, created new: the check is before KeyframeStore, which would open and recover one.
std::unique_ptr<KeyframeStore> create_store(const fs::path& file) {
  if (fs::exists(file))
    throw io::InputError(file,
                         "exists already: cvo-run --store writes a new keyframe store (remove it, or choose "
                         "another file)");
  std::vector<store::StoredRecord> recovered;
  std::string warning;
  return std::make_unique<KeyframeStore>(file, recovered, warning);
}

// The colour encoding cvo-trackerd would send keyframes with.
lcm::RgbdEncoding keyframe_encoding(const config::Config& config) {
  const auto colour = lcm::parse_colour_encoding(config.trackerd.keyframe_colour_encoding);
  if (!colour)
    throw io::InputError("trackerd.keyframe_colour_encoding",
                         "'" + config.trackerd.keyframe_colour_encoding + "': expected raw, jpeg or png");
  return {*colour, lcm::DepthEncoding::kPng};
}

}  // namespace

struct StoreOutput::State {
  State(const fs::path& file, const config::Config& config)
      : encoding(keyframe_encoding(config)),
        robot(config::robot_name(config.trackerd.robot)),
        store(create_store(file)),
        merges(*store) {}

  lcm::RgbdEncoding encoding;  // first: a bad setting fails before the file is made
  std::string robot;           // the records name it as cvo-trackerd's would (trackerd.robot)
  std::unique_ptr<KeyframeStore> store;
  store::StoreMerges merges;  // a merged keyframe's record is garbage once its merge is stored

  // Nothing is held in memory (no unsaved records): a record not written fails the run.
  void append(RecordKind kind, const std::vector<std::uint8_t>& bytes, store::RecordRef* where = nullptr) {
    if (store->append(kind, bytes, where) != Appended::kStored)
      throw io::InputError(store->file(), "cannot write the keyframe store: " + describe(store->health()));
  }
};

StoreOutput::StoreOutput(const fs::path& file, const config::Config& config)
    : state_(std::make_unique<State>(file, config)) {}

StoreOutput::~StoreOutput() = default;

void StoreOutput::keyframe(core::SessionId session, std::int64_t id, const core::RgbdFrame& frame,
                           const core::SE3& pose, const registration::PointCloud& cloud) {
  std::string error;
  const auto message =
      lcm::to_message(lcm::Keyframe{session, id, frame, pose, cloud, state_->robot}, state_->encoding, &error);
  if (!message)
    throw io::InputError(state_->store->file(), "keyframe " + std::to_string(id) + " cannot be encoded: " + error);
  store::RecordRef where;
  state_->append(RecordKind::kKeyframe, lcm::encode(*message), &where);
  state_->merges.keyframe(session, id, where);
}

void StoreOutput::local_graph(core::SessionId session, std::int64_t keyframe_id, const odometry::LocalGraph& graph) {
  const auto closed = static_cast<std::int64_t>(std::llround(graph.nodes().back().timestamp * 1e6));
  state_->append(RecordKind::kLocalGraph,
                 lcm::encode(lcm::to_message(graph, session, keyframe_id, closed, state_->robot)));
}

void StoreOutput::merge(const slam::KeyframeMerge& merge) {
  if (state_->merges.merged(merge, /*replayed=*/false, /*may_compact=*/true) != Appended::kStored)
    throw io::InputError(state_->store->file(),
                         "cannot write the keyframe store: " + describe(state_->store->health()));
}

std::uint64_t StoreOutput::records() const { return state_->store->records(); }

}  // namespace cvo::tools
