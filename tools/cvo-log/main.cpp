// cvo-log: what a cvo-slam recording says, for scripts: the tracker's poses of an LCM log (from
// lcm-logger or a file:// provider) as a TUM trajectory that cvo-eval reads, the back end's last
// map as a TUM trajectory of keyframe poses, and each process's last CVO_STATUS. Bad events are
// reported and skipped.
//
// Contract: the three subcommands, --json keys, exit codes 0 ok / 1 bad input / 2 usage error.
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <string>
#include <tuple>

#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/map_t.hpp"
#include "cvo_lcm/pose_t.hpp"
#include "cvo_lcm/status_t.hpp"
#include "libcvo/core/session.hpp"
#include "libcvo/core/trajectory.hpp"
#include "libcvo/io/input_error.hpp"
#include "libcvo/io/trajectory_io.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/map_conversion.hpp"
#include "libcvo/lcm/pose_conversion.hpp"
#include "libcvo/slam/map_robots.hpp"
#include "program/cli.hpp"
#include "program/json.hpp"

namespace {

namespace fs = std::filesystem;
using namespace cvo;

constexpr const char* kDescription =
    R"(What a cvo-slam recording (an LCM log) says, for scripts:
poses   writes the CVO_POSE messages of LOG as a TUM trajectory (odometry poses; --map: the
        map-corrected ones), stamped with the frames' colour timestamps: cvo-eval reads it.
map     writes the last CVO_MAP of LOG as a TUM trajectory of keyframe poses, stamped with the
        keyframes' colour timestamps: every keyframe of every session placed in the map, in one
        file sorted by time. Sessions the map has not placed are left out and named on stderr,
        and so is each robot's share of the map and the loops between robots.
status  prints the last CVO_STATUS of every robot's every process and session in LOG (--json:
        one object keyed by process, the last of each, with the status_t field names; and under
        "senders" every robot's, process's and session's last, each with its "process").
Bad events are reported and skipped.
)";

constexpr const char* kNotes = "map: no CVO_MAP in LOG, or one that places no keyframe, is bad input (exit 1)";

struct Arguments {
  std::string command;
  fs::path log, out;
  bool map = false, json = false;
};

CLI::App* add_command(CLI::App& app, const std::string& name, const std::string& description,
                      const std::string& synopsis, Arguments& args) {
  CLI::App* command = app.add_subcommand(name, description);
  program::describe(*command, synopsis);
  command->add_option("LOG", args.log, "the LCM log (lcm-logger, a file:// provider)")->required();
  return command;
}

void add_commands(CLI::App& app, Arguments& args) {
  CLI::App* poses = add_command(app, "poses", "the CVO_POSE messages of LOG as a TUM trajectory",
                                "cvo-log poses LOG --out TRAJ.txt [--map]", args);
  poses->add_option("--out", args.out, "the TUM trajectory to write")->required()->type_name("TRAJ.txt");
  poses->add_flag("--map", args.map, "the map-corrected poses instead of the odometry ones");
  CLI::App* map = add_command(app, "map", "the last CVO_MAP of LOG as a TUM trajectory of its placed keyframes",
                              "cvo-log map LOG --out TRAJ.txt", args);
  map->add_option("--out", args.out, "the TUM trajectory to write")->required()->type_name("TRAJ.txt");
  CLI::App* status =
      add_command(app, "status", "the last CVO_STATUS of each process in LOG", "cvo-log status LOG [--json]", args);
  status->add_flag("--json", args.json, "one JSON object keyed by process, with the status_t field names");
  app.require_subcommand(1);
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
  if (++bad <= 10)
    std::cerr << "cvo-log: " << a.log.string() << ": event " << e.eventnum << " skipped: " << error << "\n";
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
      std::cerr << "cvo-log: session " << core::session_name(session.session) << " not placed in the map: its "
                << std::count_if(last->keyframes.begin(), last->keyframes.end(), in_session) << " keyframes left out\n";
      continue;
    }
    for (const auto& k : last->keyframes)
      if (in_session(k)) trajectory.push_back({k.timestamp, k.pose});
  }
  if (trajectory.empty())
    throw io::InputError(a.log,
                         "the last CVO_MAP (revision " + std::to_string(last->revision) + ") places no keyframe");
  std::stable_sort(trajectory.begin(), trajectory.end(),
                   [](const core::StampedPose& x, const core::StampedPose& y) { return x.timestamp < y.timestamp; });
  io::write_tum_trajectory(a.out, trajectory);
  std::cerr << "cvo-log: " << trajectory.size() << " keyframe poses of map revision " << last->revision
            << " written to " << a.out.string() << "\n";
  std::cerr << "cvo-log: " << slam::describe(slam::map_robots(*last)) << "\n";
  return 0;
}

// The status_t fields, as integers and doubles like on the wire; the session first, as the
// 64-bit integer it is (scripts match "session":N).
program::Json status_json(const cvo_lcm::status_t& s) {
  program::Json o;
  o["session"] = s.session;
  o["robot"] = s.robot;
  o["utime"] = s.utime;
  o["pid"] = s.pid;
  o["state"] = int{s.state};  // an int8_t, a number rather than a character
  o["rate_hz"] = s.rate_hz;
  o["latency_median_ms"] = s.latency_median_ms;
  o["latency_p99_ms"] = s.latency_p99_ms;
  o["deadline_misses"] = s.deadline_misses;
  o["dropped_frames"] = s.dropped_frames;
  o["failed_frames"] = s.failed_frames;
  o["source_gaps"] = s.source_gaps;
  o["allocations_after_warmup"] = s.allocations_after_warmup;
  o["queue_depth"] = s.queue_depth;
  o["rss_bytes"] = s.rss_bytes;
  o["unsaved_records"] = s.unsaved_records;
  o["queue_drops"] = s.queue_drops;
  o["keyframes_requested"] = s.keyframes_requested;
  o["keyframes_recovered"] = s.keyframes_recovered;
  o["keyframes_lost"] = s.keyframes_lost;
  o["bad_messages"] = s.bad_messages;
  o["bus"] = int{s.bus};   // BUS_OPEN 0, BUS_AUTHENTICATED 1
  o["sender"] = s.sender;  // its auth_t sender id
  o["detail"] = s.detail;
  return o;
}

// One "key: value" line per field; the session in the hex form the daemons log it in.
void print_status_text(const std::string& process, const program::Json& status) {
  std::cout << process << ":\n";
  for (const auto& [key, value] : status.items()) {
    std::cout << "  " << key << ":";
    if (key == "session" || key == "sender")
      std::cout << " " << core::session_name(value.get<std::int64_t>());
    else if (value.is_array())
      for (const auto& count : value) std::cout << " " << count.dump();
    else
      std::cout << " " << (value.is_string() ? value.get<std::string>() : value.dump());
    std::cout << "\n";
  }
}

// A sender of CVO_STATUS: several trackers run the same program, on several robots, in sessions.
using Sender = std::tuple<std::string, std::string, std::int64_t>;  // robot, process, session

int print_statuses(const Arguments& a) {
  int bad = 0;
  std::map<std::string, cvo_lcm::status_t> last;  // of each process, as before robots were named
  std::map<Sender, cvo_lcm::status_t> senders;
  for_each_event(a.log, [&](const ::lcm::LogEvent& e) {
    if (e.channel != "CVO_STATUS") return;
    std::string error;
    auto m = cvo::lcm::decode<cvo_lcm::status_t>(e.data, e.datalen, &error);
    if (!m) return skipped(a, e, error, bad);
    senders[Sender{m->robot, m->process, m->session}] = *m;
    last[m->process] = std::move(*m);
  });
  if (last.empty()) throw io::InputError(a.log, "no CVO_STATUS messages");
  if (!a.json) {
    for (const auto& [sender, s] : senders) print_status_text(std::get<1>(sender), status_json(s));
    return 0;
  }
  program::Json statuses;
  for (const auto& [process, s] : last) statuses[process] = status_json(s);
  auto& every = statuses["senders"] = program::Json::array();
  for (const auto& [sender, s] : senders) {
    program::Json one;
    one["process"] = s.process;
    one.update(status_json(s));  // the process first, the detail last as in each one above
    every.push_back(std::move(one));
  }
  // On one line, as scripts grep it.
  std::cout << program::to_line(statuses);
  return 0;
}

int run(const Arguments& a) {
  if (a.command == "poses") return write_poses(a);
  if (a.command == "map") return write_map(a);
  return print_statuses(a);
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  CLI::App app(kDescription, "cvo-log");
  program::describe(app,
                    "cvo-log poses LOG --out TRAJ.txt [--map]\n"
                    "       cvo-log map LOG --out TRAJ.txt\n"
                    "       cvo-log status LOG [--json]",
                    kNotes);
  add_commands(app, args);
  return program::cli_main(app, argc, argv, [&] {
    args.command = app.get_subcommands().front()->get_name();
    return run(args);
  });
}
