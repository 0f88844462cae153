// cvo-log: what a cvo-slam recording says, for scripts: the tracker's poses of an LCM log (from
// lcm-logger or a file:// provider) as a TUM trajectory that cvo-eval reads, the back end's last
// map as a TUM trajectory of keyframe poses, and each process's last CVO_STATUS. Bad events are
// reported and skipped.
//
// Contract: the three forms below, --json keys, exit codes 0 ok / 1 bad input / 2 usage error.
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <map>
#include <string>
#include <string_view>

#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/map_t.hpp"
#include "cvo_lcm/pose_t.hpp"
#include "cvo_lcm/status_t.hpp"
#include "libcvo/core/trajectory.hpp"
#include "libcvo/io/input_error.hpp"
#include "libcvo/io/json_writer.hpp"
#include "libcvo/io/trajectory_io.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/map_conversion.hpp"
#include "libcvo/lcm/pose_conversion.hpp"
#include "tools/common/cli.hpp"

namespace {

namespace fs = std::filesystem;
using namespace cvo;

constexpr std::string_view kUsage =
    R"(usage: cvo-log poses LOG --out TRAJ.txt [--map]
       cvo-log map LOG --out TRAJ.txt
       cvo-log status LOG [--json]

poses   writes the CVO_POSE messages of LOG as a TUM trajectory (odometry poses; --map: the
        map-corrected ones), stamped with the frames' colour timestamps: cvo-eval reads it.
map     writes the last CVO_MAP of LOG as a TUM trajectory of keyframe poses, stamped with the
        keyframes' colour timestamps: every keyframe of every session placed in the map, in one
        file sorted by time. Sessions the map has not placed are left out and named on stderr.
status  prints the last CVO_STATUS of each process in LOG, with its session (--json: one object
        keyed by process, with the status_t field names).
exit status: 0 ok, 1 bad input (also: no CVO_MAP, or one that places no keyframe), 2 usage error
)";

struct Arguments {
  bool help = false;
  std::string command;
  fs::path log, out;
  bool map = false, json = false;
};

Arguments parse(int argc, char** argv) {
  Arguments a;
  for (int i = 1; i < argc; ++i) {
    const std::string_view s = argv[i];
    if (s == "--help" || s == "-h") a.help = true;
    else if (s == "--out") {
      if (++i >= argc) throw tools::UsageError("--out needs a file");
      a.out = argv[i];
    } else if (s == "--map") a.map = true;
    else if (s == "--json") a.json = true;
    else if (s.starts_with("--")) throw tools::UsageError("unknown option '" + std::string(s) + "'");
    else if (a.command.empty()) a.command = s;
    else if (a.log.empty()) a.log = s;
    else throw tools::UsageError("unexpected argument '" + std::string(s) + "'");
  }
  if (a.help) return a;
  if (a.command != "poses" && a.command != "map" && a.command != "status")
    throw tools::UsageError("expected 'poses', 'map' or 'status'");
  if (a.log.empty()) throw tools::UsageError("no LOG given");
  if ((a.command == "poses" || a.command == "map") && a.out.empty())
    throw tools::UsageError(a.command + " needs --out TRAJ.txt");
  return a;
}

template <class Visit>
void for_each_event(const fs::path& file, Visit visit) {
  if (!fs::is_regular_file(file)) throw io::InputError(file, "no such log file");
  ::lcm::LogFile log(file.string(), "r");
  if (!log.good()) throw io::InputError(file, "cannot read as an LCM log");
  while (const ::lcm::LogEvent* e = log.readNextEvent()) visit(*e);
}

// Bad events are named (the first ten) and skipped.
void skipped(const Arguments& a, const ::lcm::LogEvent& e, const std::string& error, int& bad) {
  if (++bad <= 10) std::cerr << "cvo-log: " << a.log.string() << ": event " << e.eventnum << " skipped: " << error << "\n";
}

int write_poses(const Arguments& a) {
  int bad = 0;
  core::Trajectory trajectory;
  for_each_event(a.log, [&](const ::lcm::LogEvent& e) {
    if (e.channel != "CVO_POSE") return;
    std::string error;
    const auto m = cvo::lcm::decode<cvo_lcm::pose_t>(e.data, e.datalen, &error);
    const auto pose = m ? cvo::lcm::from_message(a.map ? m->map_pose : m->odom_pose, &error) : std::nullopt;
    if (!pose) return skipped(a, e, error, bad);
    trajectory.push_back({cvo::lcm::from_utime(m->utime), *pose});
  });
  if (trajectory.empty()) throw io::InputError(a.log, "no CVO_POSE messages");
  io::write_tum_trajectory(a.out, trajectory);
  std::cerr << "cvo-log: " << trajectory.size() << " poses written to " << a.out.string() << "\n";
  return 0;
}

// The last map's placed keyframes, sorted by time: what cvo-eval scores against ground truth.
int write_map(const Arguments& a) {
  int bad = 0, maps = 0;
  std::optional<slam::Map> last;
  for_each_event(a.log, [&](const ::lcm::LogEvent& e) {
    if (e.channel != "CVO_MAP") return;
    ++maps;
    std::string error;
    const auto m = cvo::lcm::decode<cvo_lcm::map_t>(e.data, e.datalen, &error);
    auto map = m ? cvo::lcm::from_message(*m, &error) : std::nullopt;
    if (!map) return skipped(a, e, error, bad);
    last = std::move(map);
  });
  if (!last) throw io::InputError(a.log, maps == 0 ? "no CVO_MAP messages" : "no CVO_MAP message could be read");
  core::Trajectory trajectory;
  for (const auto& session : last->sessions) {
    const auto in_session = [&](const slam::MapKeyframe& k) { return k.session == session.session; };
    if (!session.placed) {
      std::cerr << "cvo-log: session " << slam::session_name(session.session)
                << " not placed in the map: its " << std::count_if(last->keyframes.begin(), last->keyframes.end(), in_session)
                << " keyframes left out\n";
      continue;
    }
    for (const auto& k : last->keyframes)
      if (in_session(k)) trajectory.push_back({k.timestamp, k.pose});
  }
  if (trajectory.empty())
    throw io::InputError(a.log, "the last CVO_MAP (revision " + std::to_string(last->revision) + ") places no keyframe");
  std::stable_sort(trajectory.begin(), trajectory.end(),
                   [](const core::StampedPose& x, const core::StampedPose& y) { return x.timestamp < y.timestamp; });
  io::write_tum_trajectory(a.out, trajectory);
  std::cerr << "cvo-log: " << trajectory.size() << " keyframe poses of map revision " << last->revision
            << " written to " << a.out.string() << "\n";
  return 0;
}

void print_status(const std::string& process, const cvo_lcm::status_t& s, bool json) {
  const std::pair<const char*, double> fields[] = {
      {"utime", static_cast<double>(s.utime)}, {"pid", s.pid}, {"state", s.state}, {"rate_hz", s.rate_hz},
      {"latency_median_ms", s.latency_median_ms}, {"latency_p99_ms", s.latency_p99_ms},
      {"deadline_misses", static_cast<double>(s.deadline_misses)}, {"dropped_frames", static_cast<double>(s.dropped_frames)},
      {"failed_frames", static_cast<double>(s.failed_frames)}, {"source_gaps", static_cast<double>(s.source_gaps)},
      {"allocations_after_warmup", static_cast<double>(s.allocations_after_warmup)},
      {"queue_depth", s.queue_depth}, {"rss_bytes", static_cast<double>(s.rss_bytes)},
      {"unsaved_records", static_cast<double>(s.unsaved_records)}, {"queue_drops", static_cast<double>(s.queue_drops)},
      {"keyframes_requested", static_cast<double>(s.keyframes_requested)},
      {"keyframes_recovered", static_cast<double>(s.keyframes_recovered)},
      {"keyframes_lost", static_cast<double>(s.keyframes_lost)}};
  if (json) {
    // The session as the 64-bit integer on the wire (a double would round it).
    std::cout << io::json_string(process) << ":{\"session\":" << s.session << ",";
    for (const auto& [k, v] : fields) std::cout << io::json_string(k) << ":" << io::json_number(v) << ",";
    std::cout << "\"bad_messages\":[";
    for (int k = 0; k < cvo_lcm::status_t::NUM_BAD_KINDS; ++k) std::cout << (k ? "," : "") << s.bad_messages[k];
    std::cout << "],\"detail\":" << io::json_string(s.detail) << "}";
    return;
  }
  std::cout << process << ":\n  session: " << slam::session_name(s.session) << "\n";
  for (const auto& [k, v] : fields) std::cout << "  " << k << ": " << io::json_number(v) << "\n";
  std::cout << "  bad_messages:";
  for (int k = 0; k < cvo_lcm::status_t::NUM_BAD_KINDS; ++k) std::cout << " " << s.bad_messages[k];
  std::cout << "\n  detail: " << s.detail << "\n";
}

int print_statuses(const Arguments& a) {
  int bad = 0;
  std::map<std::string, cvo_lcm::status_t> last;
  for_each_event(a.log, [&](const ::lcm::LogEvent& e) {
    if (e.channel != "CVO_STATUS") return;
    std::string error;
    if (auto m = cvo::lcm::decode<cvo_lcm::status_t>(e.data, e.datalen, &error)) last[m->process] = std::move(*m);
    else skipped(a, e, error, bad);
  });
  if (last.empty()) throw io::InputError(a.log, "no CVO_STATUS messages");
  if (a.json) std::cout << "{";
  bool first = true;
  for (const auto& [process, s] : last) {
    if (a.json && !first) std::cout << ",";
    print_status(process, s, a.json);
    first = false;
  }
  if (a.json) std::cout << "}\n";
  return 0;
}

int run(const Arguments& a) {
  if (a.command == "poses") return write_poses(a);
  if (a.command == "map") return write_map(a);
  return print_statuses(a);
}

}  // namespace

int main(int argc, char** argv) { return tools::cli_main("cvo-log", kUsage, argc, argv, parse, run); }
