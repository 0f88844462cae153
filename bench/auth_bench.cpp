// The cost of authenticated messages (libcvo/auth) per message: sign and verify a CVO_POSE (an
// encoded pose_t, about 800 bytes) and a CVO_KEYFRAME of about 300 kB (JPEG colour and PNG depth of
// a 640x480 keyframe, its cloud), against HMAC-SHA-512-256 (libsodium crypto_auth) on the same bytes,
// the alternative authenticator.hpp did not choose.
// Run: build/release/bin/auth_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>
#include <sodium.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "cvo_lcm/keyframe_t.hpp"
#include "cvo_lcm/pose_t.hpp"
#include "libcvo/auth/authenticator.hpp"

namespace {

using namespace cvo;

template <class Message>
std::vector<std::uint8_t> encoded(const Message& m) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

std::vector<std::uint8_t> pose_message() {
  cvo_lcm::pose_t m{};
  m.version = cvo_lcm::pose_t::SCHEMA_VERSION;
  return encoded(m);
}

// 300 kB: images of a JPEG keyframe (colour ~110 kB, depth PNG ~150 kB) and 1300 cloud points.
std::vector<std::uint8_t> keyframe_message() {
  cvo_lcm::keyframe_t m{};
  m.version = cvo_lcm::keyframe_t::SCHEMA_VERSION;
  m.num_points = 1300;
  m.xyz.assign(1300, std::vector<float>(3, 0.5F));
  m.labels.assign(1300, std::vector<float>(5, 0.25F));
  m.colour_size = 110'000;
  m.depth_size = 150'000;
  m.colour.resize(110'000);
  m.depth.resize(150'000);
  randombytes_buf(m.colour.data(), m.colour.size());
  randombytes_buf(m.depth.data(), m.depth.size());
  return encoded(m);
}

std::shared_ptr<const auth::KeyRing> keys() {
  std::vector<auth::Key> k;
  k.push_back(auth::Key::generate());
  return std::make_shared<const auth::KeyRing>(std::move(k));
}

void sign(benchmark::State& state, std::vector<std::uint8_t> message, const char* channel) {
  auth::Signer signer(keys(), 1);
  for (auto _ : state) {
    signer.sign(channel, message);
    benchmark::DoNotOptimize(message.data());
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * message.size()));
  state.counters["bytes"] = static_cast<double>(message.size());
}

// The whole check a receiver makes: trailer, key by id, authenticator, replay window (after the
// first iteration the verdict is kReplay, which costs the same: the authenticator is checked first).
void verify(benchmark::State& state, std::vector<std::uint8_t> message, const char* channel) {
  const auto ring = keys();
  auth::Signer(ring, 1).sign(channel, message);
  auth::Verifier verifier(ring, 30'000'000);
  for (auto _ : state) benchmark::DoNotOptimize(verifier.verify(channel, message.data(), message.size()));
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * message.size()));
  state.counters["bytes"] = static_cast<double>(message.size());
}

void hmac(benchmark::State& state, const std::vector<std::uint8_t>& message) {
  unsigned char key[crypto_auth_KEYBYTES], tag[crypto_auth_BYTES];
  crypto_auth_keygen(key);
  for (auto _ : state) {
    crypto_auth(tag, message.data(), message.size(), key);
    benchmark::DoNotOptimize(tag);
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * message.size()));
}

void BM_SignPose(benchmark::State& s) { sign(s, pose_message(), "CVO_POSE"); }
void BM_VerifyPose(benchmark::State& s) { verify(s, pose_message(), "CVO_POSE"); }
void BM_HmacSha512_256Pose(benchmark::State& s) { hmac(s, pose_message()); }
void BM_SignKeyframe300kB(benchmark::State& s) { sign(s, keyframe_message(), "CVO_KEYFRAME"); }
void BM_VerifyKeyframe300kB(benchmark::State& s) { verify(s, keyframe_message(), "CVO_KEYFRAME"); }
void BM_HmacSha512_256Keyframe300kB(benchmark::State& s) { hmac(s, keyframe_message()); }

BENCHMARK(BM_SignPose);
BENCHMARK(BM_VerifyPose);
BENCHMARK(BM_HmacSha512_256Pose);
BENCHMARK(BM_SignKeyframe300kB)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_VerifyKeyframe300kB)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_HmacSha512_256Keyframe300kB)->Unit(benchmark::kMicrosecond);

}  // namespace

int main(int argc, char** argv) {
  if (sodium_init() < 0) return 1;
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
