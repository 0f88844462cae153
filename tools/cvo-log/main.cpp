// cvo-log: what a cvo-slam recording says, for scripts: the tracker's poses of an LCM log (from
// lcm-logger or a file:// provider) as a TUM trajectory that cvo-eval reads, and each process's
// last CVO_STATUS. Bad events are reported and skipped.
//
// Contract: the two forms below, --json keys, exit codes 0 ok / 1 bad input / 2 usage error.
#include <filesystem>
#include <iostream>
#include <map>
#include <string>
#include <string_view>

#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/pose_t.hpp"
#include "cvo_lcm/status_t.hpp"
#include "libcvo/core/trajectory.hpp"
#include "libcvo/io/input_error.hpp"
#include "libcvo/io/json_writer.hpp"
#include "libcvo/io/trajectory_io.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/pose_conversion.hpp"
#include "tools/common/cli.hpp"

namespace {

namespace fs = std::filesystem;
using namespace cvo;

constexpr std::string_view kUsage =
    R"(usage: cvo-log poses LOG --out TRAJ.txt [--map]
       cvo-log status LOG [--json]

poses   writes the CVO_POSE messages of LOG as a TUM trajectory (odometry poses; --map: the
        map-corrected ones), stamped with the frames' colour timestamps: cvo-eval reads it.
status  prints the last CVO_STATUS of each process in LOG (--json: one object keyed by process,
        with the status_t field names).
exit status: 0 ok, 1 bad input, 2 usage error
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
  if (a.command != "poses" && a.command != "status") throw tools::UsageError("expected 'poses' or 'status'");
  if (a.log.empty()) throw tools::UsageError("no LOG given");
  if (a.command == "poses" && a.out.empty()) throw tools::UsageError("poses needs --out TRAJ.txt");
  return a;
}

template <class Visit>
void for_each_event(const fs::path& file, Visit visit) {
  if (!fs::is_regular_file(file)) throw io::InputError(file, "no such log file");
  ::lcm::LogFile log(file.string(), "r");
  if (!log.good()) throw io::InputError(file, "cannot read as an LCM log");
  while (const ::lcm::LogEvent* e = log.readNextEvent()) visit(*e);
}

int run(const Arguments& a) {
  int bad = 0;
  if (a.command == "poses") {
    core::Trajectory trajectory;
    for_each_event(a.log, [&](const ::lcm::LogEvent& e) {
      if (e.channel != "CVO_POSE") return;
      std::string error;
      const auto m = cvo::lcm::decode<cvo_lcm::pose_t>(e.data, e.datalen, &error);
      const auto pose = m ? cvo::lcm::from_message(a.map ? m->map_pose : m->odom_pose, &error) : std::nullopt;
      if (!pose) {
        if (++bad <= 10) std::cerr << "cvo-log: " << a.log.string() << ": event " << e.eventnum << " skipped: " << error << "\n";
        return;
      }
      trajectory.push_back({cvo::lcm::from_utime(m->utime), *pose});
    });
    if (trajectory.empty()) throw io::InputError(a.log, "no CVO_POSE messages");
    io::write_tum_trajectory(a.out, trajectory);
    std::cerr << "cvo-log: " << trajectory.size() << " poses written to " << a.out.string() << "\n";
    return 0;
  }
  std::map<std::string, cvo_lcm::status_t> last;
  for_each_event(a.log, [&](const ::lcm::LogEvent& e) {
    if (e.channel != "CVO_STATUS") return;
    std::string error;
    if (auto m = cvo::lcm::decode<cvo_lcm::status_t>(e.data, e.datalen, &error)) last[m->process] = std::move(*m);
    else if (++bad <= 10) std::cerr << "cvo-log: " << a.log.string() << ": event " << e.eventnum << " skipped: " << error << "\n";
  });
  if (last.empty()) throw io::InputError(a.log, "no CVO_STATUS messages");
  if (a.json) std::cout << "{";
  bool first = true;
  for (const auto& [process, s] : last) {
    const std::pair<const char*, double> fields[] = {
        {"utime", static_cast<double>(s.utime)}, {"pid", s.pid}, {"state", s.state}, {"rate_hz", s.rate_hz},
        {"latency_median_ms", s.latency_median_ms}, {"latency_p99_ms", s.latency_p99_ms},
        {"deadline_misses", static_cast<double>(s.deadline_misses)}, {"dropped_frames", static_cast<double>(s.dropped_frames)},
        {"failed_frames", static_cast<double>(s.failed_frames)}, {"source_gaps", static_cast<double>(s.source_gaps)},
        {"allocations_after_warmup", static_cast<double>(s.allocations_after_warmup)},
        {"queue_depth", s.queue_depth}, {"rss_bytes", static_cast<double>(s.rss_bytes)}};
    if (a.json) {
      std::cout << (first ? "" : ",") << io::json_string(process) << ":{";
      for (const auto& [k, v] : fields) std::cout << io::json_string(k) << ":" << io::json_number(v) << ",";
      std::cout << "\"bad_messages\":[";
      for (int k = 0; k < cvo_lcm::status_t::NUM_BAD_KINDS; ++k) std::cout << (k ? "," : "") << s.bad_messages[k];
      std::cout << "],\"detail\":" << io::json_string(s.detail) << "}";
    } else {
      std::cout << process << ":\n";
      for (const auto& [k, v] : fields) std::cout << "  " << k << ": " << io::json_number(v) << "\n";
      std::cout << "  bad_messages:";
      for (int k = 0; k < cvo_lcm::status_t::NUM_BAD_KINDS; ++k) std::cout << " " << s.bad_messages[k];
      std::cout << "\n  detail: " << s.detail << "\n";
    }
    first = false;
  }
  if (a.json) std::cout << "}\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return tools::cli_main("cvo-log", kUsage, argc, argv, parse, run); }
