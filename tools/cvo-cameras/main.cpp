// cvo-cameras: the RGB-D cameras on the USB bus (the known ids of cameras.tsv), through libusb:
// where each is plugged in, at what speed, its serial number, the --source spec that opens it and
// whether this user may open it (and if not, what to change). No camera is not an error.
//
// Contract: --json keys below, exit codes 0 ok (also with no camera) / 1 failure (the table does
// not read, libusb does not start) / 2 usage error.
#include <iostream>
#include <optional>
#include <string>
#include <string_view>

#include "drivers/usb_cameras.hpp"
#include "libcvo/io/json_writer.hpp"
#include "tools/common/cli.hpp"

namespace {

using namespace cvo;
namespace fs = std::filesystem;

constexpr std::string_view kUsage =
    R"(usage: cvo-cameras [--json] [--table FILE]

Lists the RGB-D cameras on the USB bus whose ids the camera table knows (default: cameras.tsv of
the build tree or share/cvo-slam): ids, name, bus-port, USB speed (and the speed it needs),
serial number (when this user may open the device), the --source spec that opens it, the V4L2
nodes of its interfaces, and whether this user may open it, with the reason when not.
--json prints one object: {"table": FILE, "known_ids": N, "cameras": [{"ids" ("8086:0b07"),
"name", "bus", "address", "port", "speed", "needs", "serial", "spec", "video_nodes", "node",
"accessible", "problem"}]}; "problem" is "" when there is none.
exit status: 0 ok (also when there is no camera), 1 failure, 2 usage error
)";

struct Arguments {
  bool help = false, json = false;
  std::optional<fs::path> table;
};

Arguments parse(int argc, char** argv) {
  Arguments a;
  for (int i = 1; i < argc; ++i) {
    const std::string_view s = argv[i];
    if (s == "--help" || s == "-h") a.help = true;
    else if (s == "--json") a.json = true;
    else if (s == "--table") {
      if (++i >= argc) throw tools::UsageError("--table needs a file");
      a.table = argv[i];
    } else throw tools::UsageError("unexpected argument '" + std::string(s) + "'");
  }
  return a;
}

std::string json_camera(const drivers::FoundCamera& c, const drivers::UserIds& user) {
  std::string nodes;
  for (const auto& n : c.video_nodes) nodes += (nodes.empty() ? "" : ", ") + io::json_string(n);
  const auto problem = drivers::diagnose(c, user);
  return std::string("{\"ids\": ") + io::json_string(drivers::to_string(c.known.ids)) +
         ", \"name\": " + io::json_string(c.known.name) + ", \"bus\": " + std::to_string(c.bus) +
         ", \"address\": " + std::to_string(c.address) + ", \"port\": " + io::json_string(drivers::port_text(c)) +
         ", \"speed\": " + io::json_string(drivers::to_string(c.speed)) +
         ", \"needs\": " + io::json_string(drivers::to_string(c.known.needs)) +
         ", \"serial\": " + io::json_string(c.serial) + ", \"spec\": " + io::json_string(drivers::source_spec(c)) +
         ", \"video_nodes\": [" + nodes + "], \"node\": " + io::json_string(c.node.path) +
         ", \"accessible\": " + (drivers::may_open(c.node, user) ? "true" : "false") +
         ", \"problem\": " + io::json_string(problem) + "}";
}

void print_text(const std::vector<drivers::FoundCamera>& found, const drivers::UserIds& user, std::size_t known) {
  if (found.empty()) {
    std::cout << "no RGB-D camera on the USB bus (of the " << known << " known ids)\n";
    return;
  }
  for (const auto& c : found) {
    const auto problem = drivers::diagnose(c, user);
    std::cout << drivers::identity(c) << "\n  source: " << drivers::source_spec(c);
    for (const auto& n : c.video_nodes) std::cout << (&n == &c.video_nodes.front() ? "  (V4L2 nodes: " : " ") << n;
    std::cout << (c.video_nodes.empty() ? "" : ")") << "\n  needs: " << drivers::to_string(c.known.needs)
              << "\n  access: " << (problem.empty() ? "yes (" + c.node.path + ")" : problem) << "\n";
  }
}

int run(const Arguments& args) {
  const auto file = args.table ? *args.table : drivers::default_camera_table_file();
  const auto table = drivers::CameraTable::load(file);
  const auto found = drivers::enumerate_cameras(table);
  const auto user = drivers::current_user();
  if (!args.json) {
    print_text(found, user, table.cameras().size());
    return 0;
  }
  std::cout << "{\"table\": " << io::json_string(file.string()) << ", \"known_ids\": " << table.cameras().size()
            << ", \"cameras\": [";
  for (std::size_t i = 0; i < found.size(); ++i) std::cout << (i == 0 ? "" : ", ") << json_camera(found[i], user);
  std::cout << "]}\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return tools::cli_main("cvo-cameras", kUsage, argc, argv, parse, run); }
