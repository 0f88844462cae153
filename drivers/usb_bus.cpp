// What usb_cameras.hpp needs of the system: libusb (enumeration, hot-plug), stat() of device nodes,
// this process's user and groups, sysfs for the V4L2 nodes of a USB device. The decisions on
// what it finds are in usb_cameras.cpp.
#include <grp.h>
#include <libusb.h>
#include <pwd.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdio>
#include <stdexcept>
#include <thread>

#include "drivers/usb_cameras.hpp"

namespace cvo::drivers {
namespace {

// One libusb context; contexts are independent, so each user has its own.
class UsbContext {
 public:
  UsbContext() {
    if (const int rc = libusb_init(&ctx_); rc != 0)
      throw std::runtime_error(std::string("libusb does not start: ") + libusb_error_name(rc));
  }
  ~UsbContext() { libusb_exit(ctx_); }
  UsbContext(const UsbContext&) = delete;
  UsbContext& operator=(const UsbContext&) = delete;
  [[nodiscard]] libusb_context* get() const { return ctx_; }

 private:
  libusb_context* ctx_ = nullptr;
};

UsbSpeed from_libusb(int speed) {
  switch (speed) {
    case LIBUSB_SPEED_LOW: return UsbSpeed::kLow;
    case LIBUSB_SPEED_FULL: return UsbSpeed::kFull;
    case LIBUSB_SPEED_HIGH: return UsbSpeed::kHigh;
    case LIBUSB_SPEED_SUPER: return UsbSpeed::kSuper;
    case LIBUSB_SPEED_SUPER_PLUS: return UsbSpeed::kSuperPlus;
    default: return UsbSpeed::kUnknown;
  }
}

// The serial number needs the device opened; a device this user may not open has none to show.
std::string read_serial(libusb_device* device, std::uint8_t index) {
  if (index == 0) return {};
  libusb_device_handle* handle = nullptr;
  if (libusb_open(device, &handle) != 0) return {};
  std::array<unsigned char, 256> text{};
  const int n = libusb_get_string_descriptor_ascii(handle, index, text.data(), static_cast<int>(text.size()));
  libusb_close(handle);
  return n > 0 ? std::string(reinterpret_cast<const char*>(text.data()), static_cast<std::size_t>(n)) : std::string();
}

// The /dev/videoN nodes of a USB device's interfaces: sysfs names them "<port>:<config>.<iface>".
std::vector<std::string> video_nodes(const std::string& port) {
  std::vector<std::string> nodes;
  std::error_code ec;
  for (const auto& iface : std::filesystem::directory_iterator("/sys/bus/usb/devices", ec)) {
    if (!iface.path().filename().string().starts_with(port + ":")) continue;
    for (const auto& v : std::filesystem::directory_iterator(iface.path() / "video4linux", ec))
      nodes.push_back("/dev/" + v.path().filename().string());
  }
  std::sort(nodes.begin(), nodes.end());
  return nodes;
}

std::string node_path(std::uint8_t bus, std::uint8_t address) {
  std::array<char, 32> path{};
  std::snprintf(path.data(), path.size(), "/dev/bus/usb/%03u/%03u", static_cast<unsigned>(bus),
                static_cast<unsigned>(address));
  return path.data();
}

FoundCamera describe_device(libusb_device* device, const KnownCamera& known, std::uint8_t serial_index) {
  FoundCamera camera;
  camera.known = known;
  camera.bus = libusb_get_bus_number(device);
  camera.address = libusb_get_device_address(device);
  std::array<std::uint8_t, 8> ports{};
  const int depth = libusb_get_port_numbers(device, ports.data(), static_cast<int>(ports.size()));
  if (depth > 0) camera.ports.assign(ports.begin(), ports.begin() + depth);
  camera.speed = from_libusb(libusb_get_device_speed(device));
  camera.serial = read_serial(device, serial_index);
  camera.node = node_access(node_path(camera.bus, camera.address));
  camera.video_nodes = video_nodes(port_text(camera));
  return camera;
}

// The cameras a spec opens, among those on the bus: for a v4l2 spec the one whose nodes it names,
// for an OpenNI2 URI with "@bus/address" that device; otherwise all of its scheme.
std::vector<FoundCamera> cameras_of(std::string_view spec, std::vector<FoundCamera> found) {
  const auto scheme = spec_scheme(spec);
  std::erase_if(found, [&](const FoundCamera& c) { return c.known.scheme != scheme; });
  std::vector<FoundCamera> named;
  for (const auto& c : found) {
    const bool names_node = std::any_of(c.video_nodes.begin(), c.video_nodes.end(),
                                        [&](const std::string& n) { return spec.find(n) != std::string_view::npos; });
    if (names_node || spec == source_spec(c)) named.push_back(c);
  }
  return named.empty() ? found : named;
}

std::string name_of_uid(uid_t uid) {
  const passwd* p = ::getpwuid(uid);
  return p != nullptr ? p->pw_name : std::to_string(uid);
}

std::string name_of_gid(gid_t gid) {
  const group* g = ::getgrgid(gid);
  return g != nullptr ? g->gr_name : std::to_string(gid);
}

}  // namespace

NodeAccess node_access(const std::string& path) {
  NodeAccess node;
  node.path = path;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return node;
  node.exists = true;
  node.mode = st.st_mode & 07777U;
  node.uid = st.st_uid;
  node.gid = st.st_gid;
  node.owner = name_of_uid(st.st_uid);
  node.group = name_of_gid(st.st_gid);
  return node;
}

UserIds current_user() {
  UserIds user;
  user.uid = ::geteuid();
  user.name = name_of_uid(user.uid);
  user.groups.push_back(::getegid());
  const int n = ::getgroups(0, nullptr);
  if (n > 0) {
    std::vector<gid_t> more(static_cast<std::size_t>(n));
    if (::getgroups(n, more.data()) == n) user.groups.insert(user.groups.end(), more.begin(), more.end());
  }
  return user;
}

std::vector<FoundCamera> enumerate_cameras(const CameraTable& table) {
  const UsbContext context;
  libusb_device** list = nullptr;
  const auto count = libusb_get_device_list(context.get(), &list);
  if (count < 0)
    throw std::runtime_error(std::string("libusb lists no devices: ") + libusb_error_name(static_cast<int>(count)));
  std::vector<FoundCamera> found;
  for (ssize_t i = 0; i < count; ++i) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(list[i], &d) != 0) continue;
    if (const auto* known = table.find({d.idVendor, d.idProduct}); known != nullptr)
      found.push_back(describe_device(list[i], *known, d.iSerialNumber));
  }
  libusb_free_device_list(list, 1);
  return found;
}

std::string usb_open_hint(std::string_view spec) {
  const auto scheme = spec_scheme(spec);
  if (scheme != "openni2" && scheme != "v4l2") return {};
  std::vector<NodeAccess> named;
  if (scheme == "v4l2") {
    const auto nodes = spec.substr(std::min(spec.size(), scheme.size() + 1));
    for (std::size_t begin = 0; begin <= nodes.size();) {
      const auto end = std::min(nodes.find(',', begin), nodes.size());
      if (end > begin) named.push_back(node_access(std::string(nodes.substr(begin, end - begin))));
      begin = end + 1;
    }
  }
  try {
    return explain_open_failure(spec, enumerate_cameras(CameraTable::load()), named, current_user());
  } catch (const std::exception& e) {
    return std::string("libusb cannot tell more: ") + e.what();
  }
}

std::string usb_identity(std::string_view spec) {
  try {
    std::string text;
    for (const auto& c : cameras_of(spec, enumerate_cameras(CameraTable::load())))
      text += (text.empty() ? "" : "; ") + identity(c);
    return text;
  } catch (const std::exception&) {
    return {};  // the identity is a courtesy: the source is open either way
  }
}

namespace {

// libusb's hot-plug callbacks on a thread that handles its events; the callback turns libusb's
// device into a UsbEvent for the filter, which decides.
class LibusbArrivalWatch final : public UsbArrivalWatch {
 public:
  explicit LibusbArrivalWatch(UsbArrivalFilter filter) : filter_(std::move(filter)) {
    const int rc = libusb_hotplug_register_callback(
        context_.get(), LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED | LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT, LIBUSB_HOTPLUG_NO_FLAGS,
        LIBUSB_HOTPLUG_MATCH_ANY, LIBUSB_HOTPLUG_MATCH_ANY, LIBUSB_HOTPLUG_MATCH_ANY, &LibusbArrivalWatch::callback,
        this, &handle_);
    if (rc != LIBUSB_SUCCESS) throw std::runtime_error(libusb_error_name(rc));
    thread_ = std::thread([this] {
      while (!stop_) {
        timeval tv{0, 200000};  // stop_ is seen within this, also if the interrupt is missed
        libusb_handle_events_timeout_completed(context_.get(), &tv, nullptr);
      }
    });
  }
  ~LibusbArrivalWatch() override {
    stop_ = true;
    libusb_interrupt_event_handler(context_.get());
    thread_.join();
    libusb_hotplug_deregister_callback(context_.get(), handle_);
  }
  LibusbArrivalWatch(const LibusbArrivalWatch&) = delete;
  LibusbArrivalWatch& operator=(const LibusbArrivalWatch&) = delete;

 private:
  static int LIBUSB_CALL callback(libusb_context*, libusb_device* device, libusb_hotplug_event event, void* self) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(device, &d) == 0)
      static_cast<LibusbArrivalWatch*>(self)->filter_.on_event(
          {event == LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED, UsbIds{d.idVendor, d.idProduct}});
    return 0;  // stay registered
  }

  UsbContext context_;
  UsbArrivalFilter filter_;
  libusb_hotplug_callback_handle handle_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace

std::unique_ptr<UsbArrivalWatch> UsbArrivalWatch::start(std::vector<UsbIds> ids, std::function<void()> on_arrival) {
  if (ids.empty() || libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG) == 0) return nullptr;
  try {
    return std::make_unique<LibusbArrivalWatch>(UsbArrivalFilter(std::move(ids), std::move(on_arrival)));
  } catch (const std::exception&) {
    return nullptr;  // no hot-plug here: the caller's back-off still re-opens
  }
}

}  // namespace cvo::drivers
