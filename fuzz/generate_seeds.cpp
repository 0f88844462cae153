// Writes the binary seed corpora (LCM messages and keyframe stores) into OUT/<harness>/, from the
// tests' sample messages and a small real frame, so that each seed reaches past the fingerprint and
// the counts into the conversions (real PNG and JPEG images included). The text corpora are written
// by hand. Usage: fuzz-seeds OUT (fuzz/corpus).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "fuzz/auth_harness.hpp"
#include "libcvo/lcm/chunks.hpp"
#include "libcvo/lcm/decode.hpp"
#include "libcvo/lcm/keyframe_conversion.hpp"
#include "libcvo/lcm/rgbd_conversion.hpp"
#include "libcvo/store/keyframe_store.hpp"
#include "libcvo/store/merge_record.hpp"
#include "tests/lcm/sample_messages.hpp"

namespace {

namespace fs = std::filesystem;

void write_file(const fs::path& file, const std::vector<std::uint8_t>& bytes) {
  fs::create_directories(file.parent_path());
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!out.flush()) throw std::runtime_error("cannot write " + file.string());
}

// An LCM seed, signed with the fuzzing key (fuzz/auth_harness.hpp) so that the verify step of every
// harness reaches the replay window; the same bytes are a seed of the auth harness too.
void write(const fs::path& file, std::vector<std::uint8_t> bytes) {
  cvo::auth::Signer signer(cvo::fuzz::fuzz_keys(), 0x5eed);
  signer.sign(cvo::fuzz::kFuzzChannel, bytes);
  write_file(file, bytes);
  write_file(file.parent_path().parent_path() / "auth" /
                 (file.parent_path().filename().string() + "-" + file.filename().string()),
             bytes);
}

// 8x6 with a gradient, so that PNG and JPEG are real images of a few hundred bytes.
cvo::core::RgbdFrame small_frame() {
  cvo::core::RgbdFrame frame;
  frame.index = 3;
  frame.timestamp = 1305031229.5;
  frame.depth_timestamp = 1305031229.51;
  frame.intrinsics.fx = frame.intrinsics.fy = 10;
  frame.intrinsics.cx = 4;
  frame.intrinsics.cy = 3;
  frame.intrinsics.width = 8;
  frame.intrinsics.height = 6;
  frame.intrinsics.readout_s = 0.01;  // a rolling shutter, so the seeds carry a readout
  frame.bgr.create(6, 8, CV_8UC3);
  frame.depth.create(6, 8, CV_16UC1);
  for (int y = 0; y < 6; ++y)
    for (int x = 0; x < 8; ++x) {
      frame.bgr.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uchar>(30 * x), static_cast<uchar>(40 * y), 128);
      frame.depth.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(5000 + 100 * x + 10 * y);
    }
  return frame;
}

template <class T>
T checked(std::optional<T> value, const std::string& error) {
  if (!value) throw std::runtime_error(error);
  return *value;
}

// The slices `order` (repeats allowed) of the encoded `message` (its trailer zero), named keyframe
// `id`, with its content CRC xor `crc_xor` (0: the true one).
std::vector<cvo_lcm::keyframe_chunk_t> slices(const std::vector<std::uint8_t>& message, std::int8_t kind,
                                              std::int64_t id, const std::vector<std::int32_t>& order,
                                              std::uint32_t crc_xor = 0) {
  const cvo::lcm::SlicedName name{0x5e5510'0000'0001, id, kind};
  const auto crc = cvo::lcm::content_crc(message.data(), message.size()) ^ crc_xor;
  std::vector<cvo_lcm::keyframe_chunk_t> out;
  for (const std::int32_t k : order) out.push_back(cvo::lcm::slice(message, name, crc, k));
  return out;
}

// A seed of fuzz/fuzz_keyframe_chunk.cpp: each slice signed like every LCM seed, then framed as a
// 2-byte big-endian length and its bytes.
void write_chunks(const fs::path& file, const std::vector<cvo_lcm::keyframe_chunk_t>& chunks) {
  cvo::auth::Signer signer(cvo::fuzz::fuzz_keys(), 0x5eed);
  std::vector<std::uint8_t> framed;
  for (const auto& chunk : chunks) {
    auto bytes = cvo::lcm::encode(chunk);
    signer.sign(cvo::fuzz::kFuzzChannel, bytes);
    framed.push_back(static_cast<std::uint8_t>(bytes.size() >> 8));
    framed.push_back(static_cast<std::uint8_t>(bytes.size() & 0xff));
    framed.insert(framed.end(), bytes.begin(), bytes.end());
  }
  write_file(file, framed);
}

// The keyframe_chunk seeds: the sample keyframe (one slice), the sample local graph (two) and one of
// many edges (eight), whole in order, out of order with repeats, with holes, under five names (more
// than the harness's assembly holds), and with a conflicting and a wrong CRC.
void write_chunk_seeds(const fs::path& dir) {
  using Chunk = cvo_lcm::keyframe_chunk_t;
  const auto keyframe = cvo::lcm::encode(cvo::test::sample_keyframe());
  const auto graph = cvo::lcm::encode(cvo::test::sample_local_graph());
  auto many = cvo::test::sample_local_graph();
  for (int e = 0; e < 24; ++e) many.edges.push_back(many.edges[static_cast<std::size_t>(e % 3)]);
  many.num_edges = static_cast<std::int32_t>(many.edges.size());
  const auto big = cvo::lcm::encode(many);
  const auto all = [](const std::vector<std::uint8_t>& message) {
    std::vector<std::int32_t> order(static_cast<std::size_t>(cvo::lcm::slice_count(message.size())));
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = static_cast<std::int32_t>(k);
    return order;
  };
  const auto join = [](std::vector<Chunk> a, const std::vector<Chunk>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
  };
  write_chunks(dir / "in-order", join(slices(keyframe, Chunk::KEYFRAME, 5, all(keyframe)),
                                      slices(graph, Chunk::LOCAL_GRAPH, 5, all(graph))));
  auto backwards = all(big);  // last slice first, the last two sent twice
  std::reverse(backwards.begin(), backwards.end());
  const std::vector<std::int32_t> last_two(backwards.begin(), backwards.begin() + 2);
  backwards.insert(backwards.begin() + 3, last_two.begin(), last_two.end());
  write_chunks(dir / "out-of-order", slices(big, Chunk::LOCAL_GRAPH, 6, backwards));
  write_chunks(dir / "holes", slices(big, Chunk::LOCAL_GRAPH, 6, {1, 3, 5, 1}));
  std::vector<Chunk> names;
  for (std::int64_t id = 10; id < 15; ++id) names = join(names, slices(big, Chunk::LOCAL_GRAPH, id, {0}));
  write_chunks(dir / "eviction", join(names, slices(big, Chunk::LOCAL_GRAPH, 10, all(big))));
  write_chunks(dir / "conflicting-crc",
               join(join(slices(graph, Chunk::LOCAL_GRAPH, 5, {0}), slices(graph, Chunk::LOCAL_GRAPH, 5, {1}, 1)),
                    join(slices(graph, Chunk::LOCAL_GRAPH, 5, {1}), slices(keyframe, Chunk::KEYFRAME, 5, {0}, 1))));
}

}  // namespace

int main(int argc, char** argv) try {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz-seeds OUT\n");
    return 2;
  }
  const fs::path out = argv[1];
  using cvo::lcm::encode;
  using Colour = cvo::lcm::ColourEncoding;
  using Depth = cvo::lcm::DepthEncoding;
  std::string error;

  const auto frame = small_frame();
  write(out / "rgbd/raw", encode(cvo::test::sample_rgbd()));
  const std::pair<const char*, cvo::lcm::RgbdEncoding> encodings[] = {
      {"png", {Colour::kPng, Depth::kPng}},
      {"jpeg", {Colour::kJpeg, Depth::kPng}},
      {"raw-8x6", {Colour::kRawBgr8, Depth::kRawU16Le}}};
  for (const auto& [name, encoding] : encodings)
    write(out / "rgbd" / name, encode(checked(cvo::lcm::to_message(frame, encoding, &error), error)));

  cvo::lcm::Keyframe keyframe;
  keyframe.session = 0x5e5510'0000'0001;
  keyframe.id = 2;
  keyframe.robot = "hall-a";
  keyframe.frame = frame;
  for (int p = 0; p < 3; ++p) keyframe.cloud.push_back({0.1f * p, -0.1f * p, 1.0f + p}, cvo::registration::Feature{});
  const auto keyframe_message = checked(cvo::lcm::to_message(keyframe, {Colour::kJpeg, Depth::kPng}, &error), error);
  write(out / "keyframe/jpeg-png", encode(keyframe_message));
  write(out / "keyframe/sample", encode(cvo::test::sample_keyframe()));  // images that do not decode

  const auto graph = encode(cvo::test::sample_local_graph());
  write(out / "local_graph/sample", graph);
  write(out / "map/sample", encode(cvo::test::sample_map()));
  write(out / "map_correction/sample", encode(cvo::test::sample_map_correction()));
  write(out / "status/sample", encode(cvo::test::sample_status()));
  write(out / "grid/sample", encode(cvo::test::sample_grid()));
  write_chunk_seeds(out / "keyframe_chunk");

  // A keyframe store as cvo-backendd leaves it, then the same cut short in its last record (what a
  // crash during a write leaves).
  using cvo::store::RecordKind;
  // A new store at `file`: the keyframe, its local graph, then `more` (kind, payload) records;
  // `discard_graph`: then a tombstone naming the local graph (a settled revisit's).
  const auto keyframe_store = [&](const fs::path& file,
                                  const std::vector<std::pair<RecordKind, std::vector<std::uint8_t>>>& more,
                                  bool discard_graph = false) {
    fs::create_directories(file.parent_path());
    fs::remove(file);
    std::vector<cvo::store::StoredRecord> recovered;
    std::string warning;
    cvo::store::KeyframeStore store(file, recovered, warning);
    cvo::store::RecordRef graph_at;
    store.append(RecordKind::kKeyframe, encode(keyframe_message));
    store.append(RecordKind::kLocalGraph, graph, &graph_at);
    for (const auto& [kind, payload] : more) store.append(kind, payload);
    if (discard_graph) store.discard(graph_at, /*may_compact=*/false);
  };
  const fs::path store_file = out / "keyframe_store/two-records";
  keyframe_store(store_file, {});
  // A merge record, and a store with one after its keyframe (a revisit merged, issue 27).
  cvo::slam::KeyframeMerge merge;
  merge.session = keyframe.session;
  merge.id = keyframe.id;
  merge.frame = static_cast<std::int64_t>(keyframe.frame.index);
  merge.timestamp = keyframe.frame.timestamp;
  merge.odometry = keyframe.pose;
  merge.covering_session = keyframe.session + 1;
  merge.covering_id = 3;
  merge.relative = cvo::core::SE3(Eigen::Quaterniond(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ())),
                                  Eigen::Vector3d(0.05, 0, 0.01));
  merge.gamma = 0.93;
  cvo::loop_closure::LoopClosure loop;
  loop.from = 7;
  loop.to = 12;
  loop.measurement = merge.relative;
  loop.eta = 1.5;
  loop.alpha = 0.02;
  loop.inliers = 40;
  merge.joining = {loop};
  merge.others = {loop, loop};
  const auto merge_bytes = cvo::store::encode_merge(merge);
  write(out / "merge_record/sample", merge_bytes);
  keyframe_store(out / "keyframe_store/with-merge", {{RecordKind::kMerge, merge_bytes}});
  cvo::slam::SettledEdge settled;
  settled.from_session = keyframe.session + 1;
  settled.from_id = 3;
  settled.to_session = keyframe.session + 1;
  settled.to_id = 4;
  settled.measurement = merge.relative;
  const auto settled_bytes = cvo::store::encode_settled(settled);
  write(out / "merge_record/settled", settled_bytes);
  keyframe_store(out / "keyframe_store/settled-and-discarded", {{RecordKind::kSettled, settled_bytes}}, true);
  const auto store_size = fs::file_size(store_file);
  fs::copy_file(store_file, out / "keyframe_store/torn", fs::copy_options::overwrite_existing);
  fs::resize_file(out / "keyframe_store/torn", store_size - 17);
  const std::string key_file = "cvo-slam key file 1\nkey " + std::string(cvo::fuzz::kFuzzKeyHex) + "\n";
  write_file(out / "auth/key-file", {key_file.begin(), key_file.end()});
  std::printf("fuzz-seeds: wrote %s\n", out.c_str());
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "fuzz-seeds: %s\n", e.what());
  return 1;
}
