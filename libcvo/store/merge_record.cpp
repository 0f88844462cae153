#include "libcvo/store/merge_record.hpp"

#include <bit>
#include <cmath>
#include <cstring>

namespace cvo::store {
namespace {

static_assert(std::endian::native == std::endian::little, "the store's records are little-endian");

class Writer {
 public:
  template <class T>
  void put(T value) {
    const auto at = bytes.size();
    bytes.resize(at + sizeof(T));
    std::memcpy(bytes.data() + at, &value, sizeof(T));
  }
  void pose(const core::SE3& T) {
    for (int i = 0; i < 3; ++i) put(T.translation()[i]);
    for (const double q : {T.rotation().x(), T.rotation().y(), T.rotation().z(), T.rotation().w()}) put(q);
  }
  void information(const core::Matrix6d& m) {
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) put(m(r, c));
  }
  void loops(const std::vector<loop_closure::LoopClosure>& loops) {
    put(static_cast<std::uint32_t>(loops.size()));
    for (const auto& l : loops) {
      put(l.from);
      put(l.to);
      pose(l.measurement);
      information(l.information);
      put(l.eta);
      put(l.alpha);
      put(static_cast<std::int32_t>(l.inliers));
    }
  }
  std::vector<std::uint8_t> bytes;
};

class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  template <class T>
  T get() {
    T value{};
    if (at_ + sizeof(T) > size_) {
      ok = false;
      return value;
    }
    std::memcpy(&value, data_ + at_, sizeof(T));
    at_ += sizeof(T);
    if constexpr (std::is_floating_point_v<T>)
      if (!std::isfinite(value)) ok = false;
    return value;
  }
  core::SE3 pose() {
    Eigen::Vector3d t;
    for (int i = 0; i < 3; ++i) t[i] = get<double>();  // in order (arguments of one call are not)
    const double x = get<double>(), y = get<double>(), z = get<double>(), w = get<double>();
    if (!ok || !(std::abs(w * w + x * x + y * y + z * z - 1) < 1e-6)) {
      ok = false;
      return {};
    }
    return {Eigen::Quaterniond(w, x, y, z), t};
  }
  core::Matrix6d information() {
    core::Matrix6d m;
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) m(r, c) = get<double>();
    return m;
  }
  std::vector<loop_closure::LoopClosure> loops() {
    const auto n = get<std::uint32_t>();
    std::vector<loop_closure::LoopClosure> out;
    for (std::uint32_t i = 0; ok && i < n; ++i) {
      loop_closure::LoopClosure& l = out.emplace_back();
      l.from = get<std::int64_t>();
      l.to = get<std::int64_t>();
      l.measurement = pose();
      l.information = information();
      l.eta = get<double>();
      l.alpha = get<double>();
      l.inliers = get<std::int32_t>();
    }
    return out;
  }
  [[nodiscard]] bool at_end() const { return at_ == size_; }
  bool ok = true;

 private:
  const std::uint8_t* data_;
  std::size_t size_, at_ = 0;
};

}  // namespace

std::vector<std::uint8_t> encode_merge(const slam::KeyframeMerge& m) {
  Writer w;
  w.put(kMergeRecordVersion);
  w.put(m.session);
  w.put(m.id);
  w.put(m.frame);
  w.put(m.timestamp);
  w.pose(m.odometry);
  w.put(m.covering_session);
  w.put(m.covering_id);
  w.pose(m.relative);
  w.information(m.information);
  w.put(m.gamma);
  w.loops(m.joining);
  w.loops(m.others);
  return std::move(w.bytes);
}

std::optional<slam::KeyframeMerge> decode_merge(const std::uint8_t* data, std::size_t size, std::string* error) {
  Reader r(data, size);
  if (r.get<std::uint8_t>() != kMergeRecordVersion) {
    *error = "merge record: not version " + std::to_string(kMergeRecordVersion);
    return std::nullopt;
  }
  slam::KeyframeMerge m;
  m.session = r.get<core::SessionId>();
  m.id = r.get<std::int64_t>();
  m.frame = r.get<std::int64_t>();
  m.timestamp = r.get<double>();
  m.odometry = r.pose();
  m.covering_session = r.get<core::SessionId>();
  m.covering_id = r.get<std::int64_t>();
  m.relative = r.pose();
  m.information = r.information();
  m.gamma = r.get<double>();
  m.joining = r.loops();
  m.others = r.loops();
  if (!r.ok || !r.at_end()) {
    *error = r.ok ? "merge record: bytes after its end" : "merge record: cut short or not finite";
    return std::nullopt;
  }
  return m;
}

std::vector<std::uint8_t> encode_settled(const slam::SettledEdge& e) {
  Writer w;
  w.put(kSettledRecordVersion);
  w.put(e.from_session);
  w.put(e.from_id);
  w.put(e.to_session);
  w.put(e.to_id);
  w.put(static_cast<std::uint8_t>(e.robust ? 1 : 0));
  w.pose(e.measurement);
  w.information(e.information);
  return std::move(w.bytes);
}

std::optional<slam::SettledEdge> decode_settled(const std::uint8_t* data, std::size_t size, std::string* error) {
  Reader r(data, size);
  if (r.get<std::uint8_t>() != kSettledRecordVersion) {
    *error = "settled record: not version " + std::to_string(kSettledRecordVersion);
    return std::nullopt;
  }
  slam::SettledEdge e;
  e.from_session = r.get<core::SessionId>();
  e.from_id = r.get<std::int64_t>();
  e.to_session = r.get<core::SessionId>();
  e.to_id = r.get<std::int64_t>();
  const auto robust = r.get<std::uint8_t>();
  e.robust = robust == 1;
  e.measurement = r.pose();
  e.information = r.information();
  if (!r.ok || !r.at_end() || robust > 1) {
    *error = !r.ok ? "settled record: cut short or not finite" : "settled record: bytes after its end or a bad flag";
    return std::nullopt;
  }
  return e;
}

std::vector<std::uint8_t> encode_tally(const slam::SessionTally& t) {
  Writer w;
  w.put(kTallyRecordVersion);
  w.put(t.session);
  w.put(static_cast<std::uint64_t>(t.forgotten));
  w.put(t.settled_through);
  return std::move(w.bytes);
}

std::optional<slam::SessionTally> decode_tally(const std::uint8_t* data, std::size_t size, std::string* error) {
  Reader r(data, size);
  if (r.get<std::uint8_t>() != kTallyRecordVersion) {
    *error = "tally record: not version " + std::to_string(kTallyRecordVersion);
    return std::nullopt;
  }
  slam::SessionTally t;
  t.session = r.get<core::SessionId>();
  t.forgotten = static_cast<std::size_t>(r.get<std::uint64_t>());
  t.settled_through = r.get<std::int64_t>();
  if (!r.ok || !r.at_end()) {
    *error = r.ok ? "tally record: bytes after its end" : "tally record: cut short";
    return std::nullopt;
  }
  return t;
}

}  // namespace cvo::store
