// Bytes on a 1500-byte Ethernet link per keyframe, sent whole (CVO_KEYFRAME, CVO_LOCAL_GRAPH: LCM's
// fragments of up to 64 kB, each split by IP into packets) and in slices (CVO_KEYFRAME_CHUNK: one
// packet each), for the keyframes of a tracker's recording; with what a keyframe is made of, and
// what a lossy link costs each way. A table, not Google Benchmark: sizes, not speed.
//
// Run: build/release/bin/keyframe_link_bytes LOG   (a cvo-trackerd's file:// output, keyframes whole)
//
// The model (LCM 1.3's udpm provider, lcm/udpm_util.h): a message of n bytes on a channel of c
// characters goes in one datagram of 8 + c + 1 + n bytes when that is at most 65 499, else in
// fragments of 20 header bytes plus up to 65 487 bytes (the first also carries the channel). A
// datagram of d bytes is ceil((d + 8) / 1480) IPv4 packets, d + 8 + 20 per packet bytes on the
// link (Ethernet's own framing left out). Whole, a message arrives only when every packet does:
// (1 - p)^packets, and a re-send costs all of it again, so delivering it costs bytes / (1 - p)^packets
// on average. In slices each packet is re-sent alone: bytes / (1 - p), requests left out.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "cvo_lcm/keyframe_t.hpp"
#include "libcvo/lcm/chunks.hpp"
#include "libcvo/lcm/decode.hpp"

namespace {

using cvo_lcm::keyframe_chunk_t;
constexpr std::size_t kShortMax = 65499, kFragmentPayload = 65487, kIpPayload = 1480;

struct OnLink {
  double bytes = 0;
  double packets = 0;
};

OnLink datagram(std::size_t udp_payload) {
  const auto packets = static_cast<double>((udp_payload + 8 + kIpPayload - 1) / kIpPayload);
  return {static_cast<double>(udp_payload + 8) + 20 * packets, packets};
}

OnLink whole(std::size_t n, const std::string& channel) {
  const std::size_t c = channel.size() + 1;
  if (8 + c + n <= kShortMax) return datagram(8 + c + n);
  OnLink total;
  for (std::size_t at = 0; at < n + c; at += kFragmentPayload) {
    const auto d = datagram(20 + std::min(kFragmentPayload, n + c - at));
    total.bytes += d.bytes;
    total.packets += d.packets;
  }
  return total;
}

OnLink sliced(std::size_t n) {
  constexpr auto kData = static_cast<std::size_t>(keyframe_chunk_t::MAX_DATA);
  const std::vector<std::uint8_t> one(kData);
  const auto header = static_cast<std::size_t>(cvo::lcm::slice(one, {}, 0, 0).getEncodedSize()) - kData;
  OnLink total;
  for (std::size_t at = 0; at < n; at += kData) {
    const auto d = datagram(8 + std::string("CVO_KEYFRAME_CHUNK").size() + 1 + header + std::min(kData, n - at));
    total.bytes += d.bytes;
    total.packets += d.packets;
  }
  return total;
}

struct Totals {
  int keyframes = 0;
  double message = 0, points = 0, colour = 0, depth = 0, graph = 0;  // bytes, summed
  OnLink whole_keyframe, whole_graph, sliced_keyframe, sliced_graph;
  void add(OnLink& to, const OnLink& d) {
    to.bytes += d.bytes;
    to.packets += d.packets;
  }
};

bool read(const char* file, Totals& t) {
  ::lcm::LogFile log(file, "r");
  if (!log.good()) return false;
  while (const ::lcm::LogEvent* e = log.readNextEvent()) {
    const auto n = static_cast<std::size_t>(e->datalen);
    if (e->channel == "CVO_KEYFRAME") {
      const auto k = cvo::lcm::decode<cvo_lcm::keyframe_t>(e->data, e->datalen, nullptr);
      if (!k) continue;
      ++t.keyframes;
      t.message += static_cast<double>(n);
      t.points += k->num_points * 8.0 * 4;
      t.colour += k->colour_size;
      t.depth += k->depth_size;
      t.add(t.whole_keyframe, whole(n, e->channel));
      t.add(t.sliced_keyframe, sliced(n));
    } else if (e->channel == "CVO_LOCAL_GRAPH") {
      t.graph += static_cast<double>(n);
      t.add(t.whole_graph, whole(n, e->channel));
      t.add(t.sliced_graph, sliced(n));
    }
  }
  return t.keyframes > 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: keyframe_link_bytes LOG (a cvo-trackerd's file:// output)\n");
    return 2;
  }
  Totals t;
  if (!read(argv[1], t)) {
    std::fprintf(stderr, "keyframe_link_bytes: no CVO_KEYFRAME in %s\n", argv[1]);
    return 1;
  }
  const double k = t.keyframes;
  std::printf(
      "%d keyframes; per keyframe: message %.0f bytes (points %.0f, colour %.0f, depth %.0f), local graph %.0f\n",
      t.keyframes, t.message / k, t.points / k, t.colour / k, t.depth / k, t.graph / k);
  const OnLink whole{(t.whole_keyframe.bytes + t.whole_graph.bytes) / k,
                     (t.whole_keyframe.packets + t.whole_graph.packets) / k};
  const OnLink sliced{(t.sliced_keyframe.bytes + t.sliced_graph.bytes) / k,
                      (t.sliced_keyframe.packets + t.sliced_graph.packets) / k};
  std::printf("\n| per keyframe and its local graph | whole | in slices |\n| --- | --- | --- |\n");
  std::printf("| bytes on the link, no loss | %.0f | %.0f |\n| packets | %.1f | %.1f |\n", whole.bytes, sliced.bytes,
              whole.packets, sliced.packets);
  const double keyframe_packets = t.whole_keyframe.packets / k;
  for (const double p : {0.01, 0.10, 0.30}) {
    const double arrives = std::pow(1 - p, keyframe_packets);
    std::printf("| %.0f %% loss: a keyframe sent once arrives | %.3g | (each slice: %.2f) |\n", 100 * p, arrives,
                1 - p);
    std::printf("| %.0f %% loss: bytes on the link until it arrives | %.3g | %.0f |\n", 100 * p,
                whole.bytes / std::pow(1 - p, whole.packets), sliced.bytes / (1 - p));
  }
  return 0;
}
