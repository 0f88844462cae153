#pragma once
// RGB-D cameras on the USB bus, as libusb sees them before OpenNI2 or V4L2 do: which known camera
// is plugged in where, at what speed, and whether this user may open it. Three uses:
//   - cvo-cameras lists them (enumerate_cameras);
//   - a failed openni2:/v4l2: open says why (explain_open_failure: no such device, a node this
//     user may not open, a port slower than the camera needs);
//   - ReconnectingSource re-opens on a hot-plug arrival of the camera's ids (UsbArrivalWatch)
//     instead of waiting out its back-off.
// The known ids are one data file, cameras.tsv, with the public source of every id.
//
// The decisions (may this user open the node, is the port fast enough, what to tell the user) are
// pure functions of plain data, so they are tested without a camera; only enumerate_cameras(),
// node_access() and UsbArrivalWatch talk to the system.
#include <sys/types.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cvo::drivers {

/// libusb's speeds, slowest first (so they compare).
enum class UsbSpeed { kUnknown, kLow, kFull, kHigh, kSuper, kSuperPlus };
/// "unknown", "low (1.5 Mbit/s, USB 1)", "full (12 Mbit/s, USB 1)", "high (480 Mbit/s, USB 2)", ...
const char* to_string(UsbSpeed speed);
/// The short names of the table: "low", "full", "high", "super", "super+".
std::optional<UsbSpeed> parse_usb_speed(std::string_view name);

struct UsbIds {
  std::uint16_t vendor = 0, product = 0;
  friend bool operator==(const UsbIds&, const UsbIds&) = default;
};
/// "8086:0b07".
std::string to_string(UsbIds ids);

/// One line of cameras.tsv.
struct KnownCamera {
  UsbIds ids;
  std::string name;
  std::string scheme;  // the --source scheme that opens it: "openni2" or "v4l2"
  UsbSpeed needs = UsbSpeed::kHigh;
  std::string spec;    // the --source spec that opens it, with {vendor} {product} {bus} {address}
  std::string source;  // where the ids are published
};

/// The committed drivers/cameras.tsv in a build tree, else the installed share/cvo-slam copy;
/// throws io::InputError when neither is there.
std::filesystem::path default_camera_table_file();

/// "openni2" of "openni2:any": what a spec's scheme is.
std::string_view spec_scheme(std::string_view spec);

class CameraTable {
 public:
  explicit CameraTable(std::vector<KnownCamera> cameras) : cameras_(std::move(cameras)) {}
  /// Parses cameras.tsv's text; throws io::InputError naming `file` and the line.
  static CameraTable parse(std::string_view text, const std::filesystem::path& file);
  /// Reads and parses a file; throws io::InputError.
  static CameraTable load(const std::filesystem::path& file = default_camera_table_file());

  [[nodiscard]] const std::vector<KnownCamera>& cameras() const { return cameras_; }
  [[nodiscard]] const KnownCamera* find(UsbIds ids) const;
  /// The ids of every camera opened by a spec's scheme ("openni2:..." -> the openni2 cameras).
  [[nodiscard]] std::vector<UsbIds> ids_for_spec(std::string_view spec) const;

 private:
  std::vector<KnownCamera> cameras_;
};

/// A device node's owner and permissions (stat), and the names of its owner and group.
struct NodeAccess {
  std::string path;
  bool exists = false;
  unsigned mode = 0;  // permission bits (st_mode & 07777)
  uid_t uid = 0;
  gid_t gid = 0;
  std::string owner, group;  // names; the number as text when it has none
};
/// stat() of a node; exists == false when it cannot be stat'ed.
NodeAccess node_access(const std::string& path);

/// Who this process is, for the permission check.
struct UserIds {
  uid_t uid = 0;
  std::vector<gid_t> groups;  // the primary group and the supplementary ones
  std::string name;           // for the usermod hint
};
UserIds current_user();

/// Whether `user` may open `node` for reading and writing (what libusb and V4L2 need).
bool may_open(const NodeAccess& node, const UserIds& user);

/// One camera of the table on the bus: what libusb read of it, and its /dev/bus/usb node.
struct FoundCamera {
  KnownCamera known;  // its line of the table
  std::uint8_t bus = 0, address = 0;
  std::vector<std::uint8_t> ports;  // the port path from the root hub
  UsbSpeed speed = UsbSpeed::kUnknown;
  std::string serial;                    // empty when the device cannot be opened to read it
  NodeAccess node;                       // /dev/bus/usb/BBB/DDD
  std::vector<std::string> video_nodes;  // /dev/videoN of its interfaces (V4L2 cameras), from sysfs
};

/// "1-2.3" (bus and port path, as sysfs and lsusb -t name it).
std::string port_text(const FoundCamera& camera);
/// The --source spec that opens the camera: the table's, filled in.
std::string source_spec(const FoundCamera& camera);
/// "8086:0b07 Intel RealSense D435, serial 123, high (480 Mbit/s, USB 2) on 2-1": for logs and
/// CVO_STATUS.detail.
std::string identity(const FoundCamera& camera);

/// What is wrong with a camera on the bus for this user: empty when nothing; else sentences naming
/// the node, its owner and group, and the group or udev rule to add, or the port speed.
std::string diagnose(const FoundCamera& camera, const UserIds& user);
/// The same check for a node the spec names itself (a V4L2 node): empty when it may be opened.
std::string diagnose_node(const NodeAccess& node, const UserIds& user, std::string_view rule_match);

/// What libusb adds to a failed open of `spec`: the cameras of its scheme on the bus (`on_bus`),
/// the nodes the spec names (`named_nodes`, V4L2), and `user`. Never empty for an openni2:/v4l2:
/// spec: it says there is no such camera, or what is wrong with each one, or that libusb sees no
/// problem.
std::string explain_open_failure(std::string_view spec, const std::vector<FoundCamera>& on_bus,
                                 const std::vector<NodeAccess>& named_nodes, const UserIds& user);

/// Every camera of `table` on the USB bus, through libusb. Throws std::runtime_error when libusb
/// cannot start.
std::vector<FoundCamera> enumerate_cameras(const CameraTable& table);

/// The sentence a failed open of an openni2:/v4l2: spec gets from the system (enumeration, the
/// nodes the spec names, this user); "" for other specs. Never throws: libusb or the table missing
/// is said in the sentence.
std::string usb_open_hint(std::string_view spec);
/// The identity of the camera a just-opened spec reads from, when libusb finds exactly the one(s)
/// its scheme opens; "" when it finds none or cannot tell. Never throws.
std::string usb_identity(std::string_view spec);

/// A hot-plug event as libusb reports it, as plain data.
struct UsbEvent {
  bool arrived = true;  // false: left
  UsbIds ids;
};

/// The handler libusb's hot-plug callback calls: it passes arrivals of `ids` to `on_arrival`.
class UsbArrivalFilter {
 public:
  UsbArrivalFilter(std::vector<UsbIds> ids, std::function<void()> on_arrival)
      : ids_(std::move(ids)), on_arrival_(std::move(on_arrival)) {}
  /// True when the event was one of `ids` arriving (and on_arrival was called).
  bool on_event(const UsbEvent& event) const;

 private:
  std::vector<UsbIds> ids_;
  std::function<void()> on_arrival_;
};

/// libusb's hot-plug callbacks for some ids, on a thread of its own, delivered to a
/// UsbArrivalFilter. start() returns nullptr where the platform has no hot-plug (or libusb does
/// not start): the caller then keeps polling.
class UsbArrivalWatch {
 public:
  static std::unique_ptr<UsbArrivalWatch> start(std::vector<UsbIds> ids, std::function<void()> on_arrival);
  virtual ~UsbArrivalWatch() = default;
};

}  // namespace cvo::drivers
