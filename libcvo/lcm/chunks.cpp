#include "libcvo/lcm/chunks.hpp"

#include <zlib.h>

#include <algorithm>
#include <iterator>
#include <limits>
#include <utility>

#include "libcvo/lcm/wire_layout.hpp"

namespace cvo::lcm {
namespace {

using Chunk = cvo_lcm::keyframe_chunk_t;
constexpr auto kData = static_cast<std::size_t>(Chunk::MAX_DATA);

std::size_t slice_bytes(std::size_t message_bytes, std::int32_t index) {
  const auto begin = static_cast<std::size_t>(index) * kData;
  return std::min(message_bytes, begin + kData) - begin;
}

// Runs of missing slices [first, end), the closest merged until at most max_runs are left.
std::vector<std::pair<std::int32_t, std::int32_t>> missing_runs(const std::vector<bool>& have, std::size_t max_runs) {
  std::vector<std::pair<std::int32_t, std::int32_t>> runs;
  for (std::size_t k = 0; k < have.size(); ++k) {
    if (have[k]) continue;
    const auto index = static_cast<std::int32_t>(k);
    if (!runs.empty() && runs.back().second == index)
      runs.back().second = index + 1;
    else
      runs.emplace_back(index, index + 1);
  }
  while (runs.size() > std::max<std::size_t>(max_runs, 1)) {
    std::size_t closest = 0;
    for (std::size_t i = 1; i + 1 < runs.size(); ++i)
      if (runs[i + 1].first - runs[i].second < runs[closest + 1].first - runs[closest].second) closest = i;
    runs[closest].second = runs[closest + 1].second;
    runs.erase(runs.begin() + static_cast<std::ptrdiff_t>(closest) + 1);
  }
  return runs;
}

}  // namespace

std::uint32_t content_crc(const std::uint8_t* data, std::size_t size) {
  const auto trailer = static_cast<std::size_t>(kAuthTrailerBytes);
  const std::size_t n = size >= trailer ? size - trailer : size;
  uLong c = crc32(0L, Z_NULL, 0);
  for (std::size_t at = 0; at < n;) {  // zlib takes uInt lengths
    const auto step = static_cast<uInt>(std::min<std::size_t>(n - at, 1U << 30));
    c = crc32(c, data + at, step);
    at += step;
  }
  return static_cast<std::uint32_t>(c);
}

std::int32_t slice_count(std::size_t bytes) { return static_cast<std::int32_t>((bytes + kData - 1) / kData); }

Chunk slice(std::span<const std::uint8_t> message, const SlicedName& name, std::uint32_t crc, std::int32_t index) {
  Chunk c{};
  c.version = Chunk::SCHEMA_VERSION;
  c.session = name.session;
  c.id = name.id;
  c.message = name.message;
  c.message_size = static_cast<std::int32_t>(message.size());
  c.message_crc = static_cast<std::int32_t>(crc);
  c.index = index;
  const auto begin = static_cast<std::size_t>(index) * kData;
  const auto bytes = message.subspan(begin, slice_bytes(message.size(), index));
  c.data.assign(bytes.begin(), bytes.end());
  c.data_size = static_cast<std::int32_t>(c.data.size());
  return c;
}

SliceRange clamp(SliceRange wanted, std::size_t bytes) {
  const std::int32_t n = slice_count(bytes);
  const std::int32_t first = std::clamp(wanted.first, 0, n);
  const std::int64_t end = std::min<std::int64_t>(std::int64_t{wanted.first} + std::max(wanted.count, 0), n);
  return {first, static_cast<std::int32_t>(std::max<std::int64_t>(end - first, 0))};
}

ChunkAssembly::ChunkAssembly(Limits limits) : limits_(limits) {}

std::string ChunkAssembly::check(const Chunk& c) const {
  if (c.message != Chunk::KEYFRAME && c.message != Chunk::LOCAL_GRAPH)
    return "unknown message " + std::to_string(c.message);
  const auto min_size = static_cast<std::int64_t>(8 + kAuthTrailerBytes);
  if (c.message_size < min_size || static_cast<std::uint64_t>(c.message_size) > limits_.max_bytes)
    return "message of " + std::to_string(c.message_size) + " bytes (" + std::to_string(min_size) + " to " +
           std::to_string(limits_.max_bytes) + " allowed)";
  const auto size = static_cast<std::size_t>(c.message_size);
  if (c.index < 0 || c.index >= slice_count(size))
    return "slice " + std::to_string(c.index) + " of a message of " + std::to_string(slice_count(size)) + " slices";
  if (static_cast<std::size_t>(c.data_size) != slice_bytes(size, c.index))
    return "slice " + std::to_string(c.index) + " of " + std::to_string(c.data_size) + " bytes, not " +
           std::to_string(slice_bytes(size, c.index));
  return {};
}

// The messages of `name` held in part: a range of partial_ (its keys order by name first).
std::pair<ChunkAssembly::Partials::const_iterator, ChunkAssembly::Partials::const_iterator> ChunkAssembly::of_name(
    const SlicedName& name) const {
  const auto first = partial_.lower_bound(Key{name, 0, std::numeric_limits<std::int32_t>::min()});
  auto last = first;
  while (last != partial_.end() && last->first.name == name) ++last;
  return {first, last};
}

std::size_t ChunkAssembly::of_name_count(const SlicedName& name) const {
  const auto [first, last] = of_name(name);
  return static_cast<std::size_t>(std::distance(first, last));
}

void ChunkAssembly::drop(Partials::const_iterator it) {
  for (const auto& [index, data] : it->second.slices) bytes_ -= data.size() + kSliceOverhead;
  partial_.erase(it);
}

// The weakest of [first, last): fewest slices held, then least recently added to.
bool ChunkAssembly::weaker(const Partials::value_type& a, const Partials::value_type& b) {
  return std::pair(a.second.slices.size(), a.second.touched) < std::pair(b.second.slices.size(), b.second.touched);
}

ChunkAssembly::Partials::const_iterator ChunkAssembly::weakest(Partials::const_iterator first,
                                                               Partials::const_iterator last) {
  return std::min_element(first, last, weaker);
}

void ChunkAssembly::evict(Partials::const_iterator it) {
  ++dropped_;
  dropped_slices_ += static_cast<std::int64_t>(it->second.slices.size());
  drop(it);
}

// Room for a new message of `name` whose first slice takes `bytes`: within max_per_name for its
// name and max_messages in all. What goes for room is counted (dropped()).
void ChunkAssembly::make_room(const SlicedName& name) {
  while (of_name_count(name) >= std::max<std::size_t>(limits_.max_per_name, 1)) {
    const auto [first, last] = of_name(name);
    evict(weakest(first, last));
  }
  while (!partial_.empty() && partial_.size() >= limits_.max_messages)
    evict(weakest(partial_.cbegin(), partial_.cend()));
}

// Room for `bytes` more of `keep` within max_bytes, the weakest of the others dropped first; false
// when even all the room would not do.
bool ChunkAssembly::room_for(Partials::const_iterator keep, std::size_t bytes) {
  while (bytes_ + bytes > limits_.max_bytes) {
    auto victim = partial_.cend();
    for (auto it = partial_.cbegin(); it != partial_.cend(); ++it)
      if (it != keep && (victim == partial_.cend() || weaker(*it, *victim))) victim = it;
    if (victim == partial_.cend()) return false;
    evict(victim);
  }
  return true;
}

// The last slice of `it` came: the message put together, checked against its CRC, and dropped.
ChunkAssembly::Added ChunkAssembly::complete(Partials::iterator it) {
  const Key key = it->first;
  Added done{Added::Outcome::kComplete, {}, core::BadKind::kContent, {}};
  done.message.reserve(static_cast<std::size_t>(key.size));
  for (const auto& [index, data] : it->second.slices) done.message.insert(done.message.end(), data.begin(), data.end());
  drop(it);
  if (content_crc(done.message.data(), done.message.size()) != key.crc)
    return {Added::Outcome::kRefused,
            {},
            core::BadKind::kContent,
            "the slices put together are not the message they name (CRC)"};
  return done;
}

ChunkAssembly::Added ChunkAssembly::add(const Chunk& c) {
  using Outcome = Added::Outcome;
  if (auto why = check(c); !why.empty()) return {Outcome::kRefused, {}, core::BadKind::kContent, std::move(why)};
  const Key key{{c.session, c.id, c.message}, static_cast<std::uint32_t>(c.message_crc), c.message_size};
  const std::size_t charge = c.data.size() + kSliceOverhead;
  auto it = partial_.find(key);
  if (it == partial_.end()) {
    make_room(key.name);
    it = partial_.emplace(key, Partial{{}, slice_count(static_cast<std::size_t>(c.message_size)), 0}).first;
  }
  Partial& p = it->second;
  p.touched = ++adds_;
  if (p.slices.contains(c.index)) return {Outcome::kRepeat, {}, core::BadKind::kContent, {}};
  if (!room_for(it, charge)) {  // its own slices fill the room: it goes whole
    evict(it);
    ++dropped_slices_;  // this one
    return {Outcome::kRefused, {}, core::BadKind::kContent, "a message larger than the room for messages in part"};
  }
  p.slices.emplace(c.index, c.data);
  bytes_ += charge;
  if (static_cast<std::int32_t>(p.slices.size()) < p.count) return {Outcome::kPartial, {}, core::BadKind::kContent, {}};
  return complete(it);
}

void ChunkAssembly::forget(const SlicedName& name) {
  while (true) {
    const auto [first, last] = of_name(name);
    if (first == last) return;
    drop(first);
  }
}

std::optional<std::vector<SliceRange>> ChunkAssembly::missing(const SlicedName& name, std::size_t max_ranges) const {
  const auto [first, last] = of_name(name);
  if (first == last) return std::nullopt;
  const auto most = std::max_element(
      first, last, [](const auto& a, const auto& b) { return a.second.slices.size() < b.second.slices.size(); });
  std::vector<bool> have(static_cast<std::size_t>(most->second.count));
  for (const auto& [index, data] : most->second.slices) have[static_cast<std::size_t>(index)] = true;
  std::vector<SliceRange> ranges;
  for (const auto& [from, end] : missing_runs(have, max_ranges)) ranges.push_back({from, end - from});
  return ranges;
}

}  // namespace cvo::lcm
