#include "libcvo/lcm/chunks.hpp"

#include <zlib.h>

#include <algorithm>
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

void ChunkAssembly::make_room(std::size_t bytes) {
  while (!partial_.empty() && (partial_.size() >= limits_.max_messages || bytes_ + bytes > limits_.max_bytes)) {
    const auto oldest = std::min_element(partial_.begin(), partial_.end(), [](const auto& a, const auto& b) {
      return a.second.touched < b.second.touched;
    });
    bytes_ -= oldest->second.message.size();
    partial_.erase(oldest);
    ++dropped_;
  }
}

ChunkAssembly::Added ChunkAssembly::add(const Chunk& c) {
  using Outcome = Added::Outcome;
  const auto refuse = [](core::BadKind kind, std::string why) {
    return Added{Outcome::kRefused, {}, kind, std::move(why)};
  };
  if (auto why = check(c); !why.empty()) return refuse(core::BadKind::kContent, std::move(why));
  const SlicedName name{c.session, c.id, c.message};
  const auto size = static_cast<std::size_t>(c.message_size);
  const auto crc = static_cast<std::uint32_t>(c.message_crc);
  auto it = partial_.find(name);
  if (it == partial_.end()) {
    make_room(size);
    Partial p{crc, std::vector<std::uint8_t>(size), std::vector<bool>(static_cast<std::size_t>(slice_count(size))),
              slice_count(size), 0};
    bytes_ += size;
    it = partial_.emplace(name, std::move(p)).first;
  } else if (it->second.message.size() != size || it->second.crc != crc) {
    return refuse(core::BadKind::kConflict, "a slice of another message than the one of this name held in part");
  }
  Partial& p = it->second;
  p.touched = ++adds_;
  const auto index = static_cast<std::size_t>(c.index);
  if (p.have[index]) return {Outcome::kRepeat, {}, core::BadKind::kContent, {}};
  std::copy(c.data.begin(), c.data.end(), p.message.begin() + static_cast<std::ptrdiff_t>(index * kData));
  p.have[index] = true;
  if (--p.missing > 0) return {Outcome::kPartial, {}, core::BadKind::kContent, {}};
  Added done{Outcome::kComplete, std::move(p.message), core::BadKind::kContent, {}};
  bytes_ -= size;
  partial_.erase(it);
  if (content_crc(done.message.data(), done.message.size()) != crc)
    return refuse(core::BadKind::kContent, "the slices put together are not the message they name (CRC)");
  return done;
}

std::optional<std::vector<SliceRange>> ChunkAssembly::missing(const SlicedName& name, std::size_t max_ranges) const {
  const auto it = partial_.find(name);
  if (it == partial_.end()) return std::nullopt;
  std::vector<SliceRange> ranges;
  for (const auto& [first, end] : missing_runs(it->second.have, max_ranges)) ranges.push_back({first, end - first});
  return ranges;
}

}  // namespace cvo::lcm
