// The camera table and the diagnoses: pure functions of plain data (the system calls are in
// usb_bus.cpp), so every decision is tested on constructed cases.
#include "drivers/usb_cameras.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "libcvo/io/input_error.hpp"

namespace cvo::drivers {
namespace {

struct SpeedName {
  UsbSpeed speed;
  const char* name;
  const char* text;
};
constexpr std::array<SpeedName, 6> kSpeeds{{
    {UsbSpeed::kUnknown, "unknown", "unknown"},
    {UsbSpeed::kLow, "low", "low (1.5 Mbit/s, USB 1)"},
    {UsbSpeed::kFull, "full", "full (12 Mbit/s, USB 1)"},
    {UsbSpeed::kHigh, "high", "high (480 Mbit/s, USB 2)"},
    {UsbSpeed::kSuper, "super", "super (5 Gbit/s, USB 3)"},
    {UsbSpeed::kSuperPlus, "super+", "super+ (10 Gbit/s, USB 3.1)"},
}};

std::vector<std::string_view> split(std::string_view text, char sep) {
  std::vector<std::string_view> parts;
  for (std::size_t begin = 0;;) {
    const auto end = text.find(sep, begin);
    parts.push_back(text.substr(begin, end == std::string_view::npos ? std::string_view::npos : end - begin));
    if (end == std::string_view::npos) return parts;
    begin = end + 1;
  }
}

std::optional<std::uint16_t> parse_hex16(std::string_view s) {
  std::uint16_t v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v, 16);
  if (s.size() != 4 || ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

std::string hex4(std::uint16_t v) {
  std::array<char, 8> buf{};
  std::snprintf(buf.data(), buf.size(), "%04x", static_cast<unsigned>(v));
  return buf.data();
}

void replace_all(std::string& s, std::string_view what, const std::string& with) {
  for (auto at = s.find(what); at != std::string::npos; at = s.find(what, at + with.size()))
    s.replace(at, what.size(), with);
}

// "crw-rw-r--" for a character device node's permission bits.
std::string mode_text(unsigned mode) {
  std::string text = "c";
  for (int shift = 6; shift >= 0; shift -= 3) {
    text += (mode >> shift & 4U) != 0 ? 'r' : '-';
    text += (mode >> shift & 2U) != 0 ? 'w' : '-';
    text += (mode >> shift & 1U) != 0 ? 'x' : '-';
  }
  return text;
}

bool in_group(const UserIds& user, gid_t gid) {
  return std::find(user.groups.begin(), user.groups.end(), gid) != user.groups.end();
}

std::string usb_rule_match(UsbIds ids) {
  return "SUBSYSTEM==\"usb\", ATTR{idVendor}==\"" + hex4(ids.vendor) + "\", ATTR{idProduct}==\"" + hex4(ids.product) +
         "\"";
}

}  // namespace

std::string_view spec_scheme(std::string_view spec) { return spec.substr(0, spec.find(':')); }

const char* to_string(UsbSpeed speed) {
  for (const auto& s : kSpeeds)
    if (s.speed == speed) return s.text;
  return "unknown";
}

std::optional<UsbSpeed> parse_usb_speed(std::string_view name) {
  for (const auto& s : kSpeeds)
    if (s.speed != UsbSpeed::kUnknown && name == s.name) return s.speed;
  return std::nullopt;
}

std::string to_string(UsbIds ids) { return hex4(ids.vendor) + ":" + hex4(ids.product); }

CameraTable CameraTable::parse(std::string_view text, const std::filesystem::path& file) {
  static constexpr std::array<std::string_view, 7> kHeader{"vendor", "product", "name",  "scheme",
                                                           "speed",  "spec",    "source"};
  std::vector<KnownCamera> cameras;
  bool header = false;
  std::size_t number = 0;
  for (auto line : split(text, '\n')) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.empty() || line.front() == '#') continue;
    const auto f = split(line, '\t');
    if (f.size() != kHeader.size())
      throw io::InputError(
          file, number,
          "expected " + std::to_string(kHeader.size()) + " tab-separated columns, found " + std::to_string(f.size()));
    if (!header) {
      if (!std::equal(f.begin(), f.end(), kHeader.begin()))
        throw io::InputError(file, number, "expected the header: vendor product name scheme speed spec source");
      header = true;
      continue;
    }
    const auto vendor = parse_hex16(f[0]), product = parse_hex16(f[1]);
    if (!vendor || !product) throw io::InputError(file, number, "vendor and product are 4 hex digits");
    if (f[3] != "openni2" && f[3] != "v4l2") throw io::InputError(file, number, "scheme is openni2 or v4l2");
    const auto speed = parse_usb_speed(f[4]);
    if (!speed) throw io::InputError(file, number, "speed is low, full, high, super or super+");
    if (!f[5].starts_with(std::string(f[3]) + ":")) throw io::InputError(file, number, "spec must use the scheme");
    if (f[6].empty()) throw io::InputError(file, number, "every id needs its source");
    const UsbIds ids{*vendor, *product};
    if (std::any_of(cameras.begin(), cameras.end(), [&](const KnownCamera& c) { return c.ids == ids; }))
      throw io::InputError(file, number, to_string(ids) + " is listed twice");
    cameras.push_back({ids, std::string(f[2]), std::string(f[3]), *speed, std::string(f[5]), std::string(f[6])});
  }
  if (!header) throw io::InputError(file, "no header line: vendor product name scheme speed spec source");
  return CameraTable(std::move(cameras));
}

CameraTable CameraTable::load(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw io::InputError(file, "cannot read the camera table");
  std::ostringstream text;
  text << in.rdbuf();
  return parse(text.str(), file);
}

const KnownCamera* CameraTable::find(UsbIds ids) const {
  const auto it = std::find_if(cameras_.begin(), cameras_.end(), [&](const KnownCamera& c) { return c.ids == ids; });
  return it == cameras_.end() ? nullptr : &*it;
}

std::vector<UsbIds> CameraTable::ids_for_spec(std::string_view spec) const {
  std::vector<UsbIds> ids;
  for (const auto& c : cameras_)
    if (c.scheme == spec_scheme(spec)) ids.push_back(c.ids);
  return ids;
}

std::filesystem::path default_camera_table_file() {
  const std::filesystem::path committed = CVO_COMMITTED_CAMERAS, installed = CVO_INSTALLED_CAMERAS;
  if (std::filesystem::is_regular_file(committed)) return committed;
  if (std::filesystem::is_regular_file(installed)) return installed;
  throw io::InputError(installed, "camera table not found (nor " + committed.string() + "): install cvo-slam");
}

bool may_open(const NodeAccess& node, const UserIds& user) {
  if (!node.exists) return false;
  if (user.uid == 0) return true;  // root opens any node
  // The kernel's order: the owner's bits for the owner, else the group's for a member, else others'.
  const unsigned shift = node.uid == user.uid ? 6U : in_group(user, node.gid) ? 3U : 0U;
  return ((node.mode >> shift) & 06U) == 06U;
}

std::string port_text(const FoundCamera& camera) {
  std::string text = std::to_string(camera.bus);
  for (std::size_t i = 0; i < camera.ports.size(); ++i)
    text.append(i == 0 ? "-" : ".").append(std::to_string(camera.ports[i]));
  return text;
}

std::string source_spec(const FoundCamera& camera) {
  std::string spec = camera.known.spec;
  replace_all(spec, "{vendor}", hex4(camera.known.ids.vendor));
  replace_all(spec, "{product}", hex4(camera.known.ids.product));
  replace_all(spec, "{bus}", std::to_string(camera.bus));
  replace_all(spec, "{address}", std::to_string(camera.address));
  return spec;
}

std::string identity(const FoundCamera& camera) {
  return to_string(camera.known.ids) + " " + camera.known.name +
         (camera.serial.empty() ? "" : ", serial " + camera.serial) + ", " + to_string(camera.speed) + " on " +
         port_text(camera);
}

std::string diagnose_node(const NodeAccess& node, const UserIds& user, std::string_view rule_match) {
  if (!node.exists) return node.path + " does not exist";
  if (may_open(node, user)) return {};
  std::string why = node.path + " is " + mode_text(node.mode) + " " + node.owner + ":" + node.group + " and user " +
                    user.name + " may not read and write it: ";
  // A group that may read and write: joining it is enough; else a udev rule must grant a group.
  if ((node.mode & 060U) == 060U && node.gid != 0)
    return why + "add the user to group " + node.group + " (sudo usermod -aG " + node.group + " " + user.name +
           ", then log in again)";
  return why + "add a udev rule (e.g. /etc/udev/rules.d/99-cvo-cameras.rules: " + std::string(rule_match) +
         ", MODE=\"0660\", GROUP=\"plugdev\"; then sudo udevadm control --reload-rules, replug) and add the user to "
         "group plugdev (sudo usermod -aG plugdev " +
         user.name + ")";
}

std::string diagnose(const FoundCamera& camera, const UserIds& user) {
  std::string problems = diagnose_node(camera.node, user, usb_rule_match(camera.known.ids));
  if (camera.speed != UsbSpeed::kUnknown && camera.speed < camera.known.needs) {
    problems += (problems.empty() ? "" : "; ");
    problems += std::string("it is connected at ") + to_string(camera.speed) + " but needs " +
                to_string(camera.known.needs) + ": plug it into a port (and cable) of that speed";
  }
  return problems;
}

std::string explain_open_failure(std::string_view spec, const std::vector<FoundCamera>& on_bus,
                                 const std::vector<NodeAccess>& named_nodes, const UserIds& user) {
  std::vector<std::string> said;
  for (const auto& node : named_nodes)
    if (auto why = diagnose_node(node, user, "KERNEL==\"" + node.path.substr(node.path.rfind('/') + 1) + "\"");
        !why.empty())
      said.push_back(std::move(why));
  bool any = false;
  for (const auto& camera : on_bus) {
    if (camera.known.scheme != spec_scheme(spec)) continue;
    any = true;
    const auto why = diagnose(camera, user);
    said.push_back(identity(camera) + ": " + (why.empty() ? "libusb sees no problem with it" : why));
  }
  if (!any)
    said.push_back("no " + std::string(spec_scheme(spec)) +
                   " camera of the known ids on the USB bus (cvo-cameras lists the cameras it sees)");
  std::string text = "libusb: ";
  for (std::size_t i = 0; i < said.size(); ++i) text += (i == 0 ? "" : "; ") + said[i];
  return text;
}

bool UsbArrivalFilter::on_event(const UsbEvent& event) const {
  if (!event.arrived || std::find(ids_.begin(), ids_.end(), event.ids) == ids_.end()) return false;
  on_arrival_();
  return true;
}

}  // namespace cvo::drivers
