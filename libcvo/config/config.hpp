#pragma once
// Every tunable of the system in one value, read from YAML and from command-line overrides.
//
// The YAML mirrors the structs: a top-level section per parameter group, keyed by member name,
//     cvo:
//       ell_init: 0.1
//     camera: tum_fr1
// A file may give any subset; the rest keep their defaults (the paper's Table 1 and the tuned
// values, see libcvo/core/parameters.hpp). Two structs share a section where the paper's values
// and a module's own settings belong together: keyframe (KeyframeParameters, then KF-CVO's
// KeyframeTrackingParameters) and loop_closure (LoopClosureParameters, then
// LoopVerificationParameters). libcvo/config/default.yaml is dump_config(Config{}), every key
// with a comment. One table in config.cpp lists every key with its member and its valid range;
// loading, overrides, dumping and comparing all walk it, so a new parameter is one new row (and
// its field in libcvo/core/parameters.hpp; module_parameters.cpp hands the sections to the modules
// whole).
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "libcvo/core/parameters.hpp"
#include "libcvo/io/input_error.hpp"

namespace cvo::config {

/// cvo-trackerd's own settings (daemon/trackerd): where frames come from, where results go, and how
/// the realtime tracking thread runs. The tracker's maths is configured by the sections above.
/// trackerd.robot's value that names the robot by its host's name (not a name: '$' is no host
/// name's character).
inline constexpr std::string_view kHostName = "$HOSTNAME";

struct TrackerdParameters {
  std::string source = "openni2:any";
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  bool paced = true;
  bool exit_on_eof = false;
  std::size_t ring_slots = 4;  // ~130 ms at 30 Hz: a hiccup is absorbed, a slow tracker sheds load
  bool deterministic = false;
  int realtime_priority = 40;  // SCHED_FIFO, below threaded IRQ handlers (50) so camera interrupts go first
  int cpu = -1;
  bool lock_memory = true;
  double deadline_ms = 33.3;  // one frame period at 30 Hz
  std::size_t warmup_frames = 30;
  std::string keyframe_colour_encoding = "jpeg";
  // Keyframes and local graphs in slices of one datagram (CVO_KEYFRAME_CHUNK), whole, or auto: whole
  // into a file:// log (nothing is lost there), in slices on a network (libcvo/lcm/chunks.hpp).
  std::string keyframe_transport = "auto";
  double status_period_s = 1.0;
  // Keyframes (with their local graphs) kept, as sent, to answer CVO_KEYFRAME_REQUEST; each slot is
  // preallocated for the largest message (about 2.2 MB at 640x480).
  std::size_t keyframe_history = 32;
  // Bytes a second that CVO_KEYFRAME_REQUESTs may make the tracker send again, per requester and
  // per session (daemon/trackerd/resend_budget.hpp).
  double resend_bytes_per_s = 2e6;
  // Frames of another camera (size or intrinsics) in a row that make the tracker re-initialise for
  // it in a new session; fewer are refused as bad content (a lone odd frame does not reset tracking).
  std::size_t camera_change_frames = 5;
  // A CVO_MAP whose correction of the running session moves the map frame further than this from
  // the correction applied last is refused as implausible (a loop closure corrects drift).
  double max_map_jump_m = 1.0;
  double max_map_jump_deg = 30.0;
  // Guards on the order of CVO_MAPs (libcvo/lcm/map_decision.hpp): an epoch further than this in
  // the future of this machine's clock, and a revision further ahead of the applied one than this
  // many per second since it was applied, are refused as implausible.
  double map_epoch_slack_s = 10.0;
  double map_revisions_per_s = 100.0;
  // The map pose published while the back end has not localized the session: its odometry pose
  // (a pose in the session's own frame, as before any map), or none (map_pose left out: a consumer
  // that needs the map frame waits).
  std::string map_pose_until_localized = "odometry";
  // The robot this tracker speaks for, in its messages (CVO_STATUS); kHostName: the host's name.
  std::string robot = std::string(kHostName);
  // Issue 28: what the back end has not acknowledged yet is kept in this directory ("none": nowhere)
  // across a crash, up to spool_bytes, and waited for at a clean exit for up to linger_s.
  std::string spool = "none";
  std::size_t spool_bytes = std::size_t{512} << 20;
  double linger_s = 10.0;
};

/// Whether cvo-trackerd sends keyframes in slices (trackerd.keyframe_transport, resolved for its lcm_url).
bool keyframes_in_chunks(const TrackerdParameters& trackerd);

/// cvo-backendd's own settings (daemon/backendd).
struct BackenddParameters {
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
  std::string store = "/var/lib/cvo-slam/keyframes.store";
  std::string vocabulary = "default";  // the installed default (share/cvo-slam/orb_k10_l4.voc), or a file
  double status_period_s = 1.0;
  // The full CVO_MAP (O(N) bytes) goes out at most this often while the map changes, at once after a
  // loop closure or a join, and at the stop; each changed session's CVO_MAP_CORRECTION after every
  // change. 0: the full map after every change too.
  double map_period_s = 5.0;
  // A signal stop (SIGTERM: systemd's stop) ends within this many seconds, below the unit's
  // TimeoutStopSec (30 s): records still waiting are in the store and the next start applies them,
  // and the final global optimisation gets what time is left.
  double stop_timeout_s = 20.0;
  std::string publish_url = "lcm_url";  // where CVO_MAP and CVO_STATUS go; "lcm_url": the same provider
  bool exit_on_eof = false;             // a file:// lcm_url that ends: final optimisation, final map, exit 0
  std::size_t queue_max = 64;           // records waiting for the back end's thread in memory; more wait in the store
  // Accepted records held in memory while the keyframe store cannot be written (disk full, file
  // size limit), written in order when it works again; beyond this they are used but not stored.
  // A 640x480 keyframe with JPEG colour is about 300 kB.
  std::size_t unsaved_records_max = 512;
  // Records (keyframes and local graphs) one session, and one sender, may store; past either a
  // record is refused (daemon/backendd/record_quota.hpp).
  std::size_t max_records_per_session = 200000;
  std::size_t max_records_per_sender = 1000000;
  // mapping: every session grows the stored map; localization: the stored map is read only and
  // every session is localized in it (keyframes kept in memory, never stored).
  std::string mode = "mapping";
};

/// Authenticated messages on the bus (libcvo/auth): both daemons and every program that puts
/// messages on the bus read the same key file.
struct AuthParameters {
  // The deployment key file (cvo-keygen; mode 0600), e.g. $CREDENTIALS_DIRECTORY/cvo-slam.key under
  // systemd; none: an open bus, nothing signed or verified (said at start and in CVO_STATUS).
  std::string key_file = "none";
  // A message whose counter (its sender's clock, µs) is older than this by the receiver's clock is
  // refused as a replay: a recording played back, or a sender whose clock is this far behind.
  double max_age_s = 30.0;
};

struct Config {
  core::SelectionParameters selection;
  core::CvoParameters cvo;
  core::OdometryParameters odometry;
  core::KeyframeParameters keyframe;
  core::KeyframeTrackingParameters keyframe_tracking;  // YAML section keyframe
  core::LoopClosureParameters loop_closure;
  core::LoopVerificationParameters loop_verification;  // YAML section loop_closure
  core::PoseGraphParameters pose_graph;
  core::DatasetParameters dataset;
  core::MappingParameters mapping;
  core::LocalizationParameters localization;
  TrackerdParameters trackerd;
  BackenddParameters backendd;
  AuthParameters auth;
  std::string camera = "tum_fr1";  // a preset name or a path to an intrinsics file (io::load_camera)
};

/// Every key of the table is equal (doubles exactly).
bool operator==(const Config& a, const Config& b);

/// A bad configuration: names the source (file, or "--set" for an override), the line when known,
/// the full key ("cvo.ell_init") and the offending value.
class ConfigError : public io::InputError {
 public:
  using io::InputError::InputError;
};

/// Reads a YAML file; throws ConfigError on an unreadable file, a YAML syntax error, an unknown
/// section or key (with a suggestion), a duplicate key, a value of the wrong type or out of
/// range (NaN included), or inconsistent values (e.g. selection.min_depth_m >= max_depth_m).
Config load_config(const std::filesystem::path& file);
Config parse_config(std::string_view yaml_text, const std::filesystem::path& name_for_errors = "<config>");

/// Applies one "--set" assignment "section.key=value" with the same checks; on error the config
/// is left unchanged.
void apply_override(Config& config, std::string_view assignment);

/// A complete YAML document with every key, its value (round-trip precision) and a comment;
/// parse_config(dump_config(c)) == c.
std::string dump_config(const Config& config);

/// Every full key ("selection.target_points", ..., "camera") in table order.
std::vector<std::string> config_keys();

/// The robot a process speaks for: `configured` (trackerd.robot), or this machine's host name when
/// that is kHostName ("localhost" when the host has none or one that is no robot name).
std::string robot_name(std::string_view configured);

}  // namespace cvo::config
