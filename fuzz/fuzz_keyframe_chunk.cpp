// CVO_KEYFRAME_CHUNK as cvo-backendd receives it: each slice decoded, then put together with the
// slices before it by one ChunkAssembly (libcvo/lcm/chunks.hpp). The assembly's paths (holes, a
// repeat, a conflict, the CRC of a message put together, eviction) are reached only by a sequence of
// slices, so an input is several LCM buffers: up to 64, each a 2-byte big-endian length and that many
// bytes (a length past the end takes the rest; a last lone byte is ignored). The limits are small so
// that eviction runs. Checked after every slice, what a receiver relies on: the ranges it asks for
// again (missing()), a complete message's size and CRC, nothing of its name held once it is let in
// (forget()), and the assembly's bounds.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "cvo_lcm/keyframe_chunk_t.hpp"
#include "fuzz/lcm_harness.hpp"
#include "libcvo/lcm/chunks.hpp"

namespace {

using cvo::fuzz::fail;
using cvo::lcm::ChunkAssembly;
using Chunk = cvo_lcm::keyframe_chunk_t;
using Outcome = ChunkAssembly::Added::Outcome;

const ChunkAssembly::Limits kLimits{4, 64 * 1024};
constexpr std::size_t kMaxBuffers = 64;

// The buffers of the input (the framing above).
std::vector<std::span<const std::uint8_t>> split(const std::uint8_t* data, std::size_t size) {
  std::vector<std::span<const std::uint8_t>> buffers;
  std::size_t at = 0;
  while (buffers.size() < kMaxBuffers && size - at >= 2) {
    const std::size_t length = (std::size_t{data[at]} << 8) | data[at + 1];
    at += 2;
    const std::size_t n = std::min(length, size - at);
    buffers.emplace_back(data + at, n);
    at += n;
  }
  return buffers;
}

// missing(name, max_ranges) of the chunk's name, after the chunk was added with `outcome`.
void check_missing(const ChunkAssembly& assembly, const Chunk& chunk, Outcome outcome, std::size_t max_ranges) {
  const auto ranges = assembly.missing({chunk.session, chunk.id, chunk.message}, max_ranges);
  if (outcome == Outcome::kPartial && (!ranges || ranges->empty())) fail("a message held in part misses nothing");
  if (!ranges) return;
  if (ranges->size() > max_ranges)
    fail(std::to_string(ranges->size()) + " missing ranges, at most " + std::to_string(max_ranges) + " asked for");
  // Messages of the name that compete with the chunk's (another CRC or size) are held too, and the
  // ranges are of the one holding the most: within the largest message the limits let in.
  const std::int64_t slices = cvo::lcm::slice_count(kLimits.max_bytes);
  std::int64_t end = 0;
  for (const auto& range : *ranges) {
    if (range.count < 1) fail("a missing range of " + std::to_string(range.count) + " slices");
    if (range.first < end) fail("missing ranges not ascending and disjoint (or before slice 0)");
    end = std::int64_t{range.first} + range.count;
    if (end > slices) fail("a missing range past the message's " + std::to_string(slices) + " slices");
  }
}

void add(ChunkAssembly& assembly, const Chunk& chunk) {
  const auto added = assembly.add(chunk);
  if (added.outcome == Outcome::kComplete) {
    if (added.message.size() != static_cast<std::size_t>(chunk.message_size))
      fail("a message put together of " + std::to_string(added.message.size()) + " bytes, not " +
           std::to_string(chunk.message_size));
    if (cvo::lcm::content_crc(added.message.data(), added.message.size()) !=
        static_cast<std::uint32_t>(chunk.message_crc))
      fail("a message put together whose CRC is not the one its slices name");
  }
  for (const std::size_t max_ranges : {std::size_t{1}, std::size_t{3}})
    check_missing(assembly, chunk, added.outcome, max_ranges);
  if (added.outcome == Outcome::kComplete) {  // let in, as the back end does: the rest competed in vain
    const cvo::lcm::SlicedName name{chunk.session, chunk.id, chunk.message};
    assembly.forget(name);
    if (assembly.missing(name, 1)) fail("a name let in is still held in part after forget()");
  }
  if (assembly.bytes() > kLimits.max_bytes || assembly.held() > kLimits.max_messages)
    fail("the assembly holds " + std::to_string(assembly.held()) + " messages of " + std::to_string(assembly.bytes()) +
         " bytes, beyond its limits");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ChunkAssembly assembly(kLimits);
  for (const auto buffer : split(data, size))
    cvo::fuzz::fuzz_message<Chunk>(buffer.data(), buffer.size(), [&](const Chunk& chunk) { add(assembly, chunk); });
  return 0;
}
