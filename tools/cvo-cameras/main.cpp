// cvo-cameras: the RGB-D cameras on the USB bus (the known ids of cameras.tsv), through libusb:
// where each is plugged in, at what speed, its serial number, the --source spec that opens it and
// whether this user may open it (and if not, what to change). No camera is not an error.
//
// Contract: --json keys below, exit codes 0 ok (also with no camera) / 1 failure (the table does
// not read, libusb does not start) / 2 usage error.
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "drivers/usb_cameras.hpp"
#include "program/cli.hpp"
#include "program/json.hpp"

namespace {

using namespace cvo;
namespace fs = std::filesystem;

constexpr const char* kDescription =
    R"(Lists the RGB-D cameras on the USB bus whose ids the camera table knows: ids, name, bus-port, USB
speed (and the speed it needs), serial number (when this user may open the device), the --source
spec that opens it, the V4L2 nodes of its interfaces, and whether this user may open it, with the
reason when not.
)";

constexpr const char* kNotes =
    R"(--json prints one object: {"table": FILE, "known_ids": N, "cameras": [{"ids" ("8086:0b07"),
"name", "bus", "address", "port", "speed", "needs", "serial", "spec", "video_nodes", "node",
"accessible", "problem"}]}; "problem" is "" when there is none.
No camera on the bus is not an error (exit 0).)";

struct Arguments {
  bool json = false;
  std::optional<fs::path> table;
};

void add_options(CLI::App& app, Arguments& args) {
  app.add_flag("--json", args.json, "print one JSON object instead of the list");
  app.add_option("--table", args.table, "the camera table (default: cameras.tsv of the build tree or share/cvo-slam)")
      ->type_name("FILE");
}

program::Json camera_json(const drivers::FoundCamera& c, const drivers::UserIds& user) {
  program::Json o;
  o["ids"] = drivers::to_string(c.known.ids);
  o["name"] = c.known.name;
  o["bus"] = int{c.bus};  // uint8_t: a number, not a character
  o["address"] = int{c.address};
  o["port"] = drivers::port_text(c);
  o["speed"] = drivers::to_string(c.speed);
  o["needs"] = drivers::to_string(c.known.needs);
  o["serial"] = c.serial;
  o["spec"] = drivers::source_spec(c);
  o["video_nodes"] = c.video_nodes;
  o["node"] = c.node.path;
  o["accessible"] = drivers::may_open(c.node, user);
  o["problem"] = drivers::diagnose(c, user);
  return o;
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
  program::Json o;
  o["table"] = file.string();
  o["known_ids"] = table.cameras().size();
  o["cameras"] = program::Json::array();
  for (const auto& camera : found) o["cameras"].push_back(camera_json(camera, user));
  std::cout << program::to_text(o);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  CLI::App app(kDescription, "cvo-cameras");
  program::describe(app, "cvo-cameras [--json] [--table FILE]", kNotes);
  add_options(app, args);
  return program::cli_main(app, argc, argv, [&] { return run(args); });
}
