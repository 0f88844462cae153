// Image coding, ours (libcvo/image: libpng, TurboJPEG, libwebp) side by side with OpenCV's
// cv::imencode / cv::imdecode, on a real 640x480 frame of the embedded sample: colour PNG, colour
// JPEG at the keyframe encoder's quality (lcm::RgbdEncoding's default), 16-bit depth PNG, and the
// sample's own lossless WebP colour. PNG at compression 1, the messages' default.
// Run: build/release/bin/image_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "libcvo/image/jpeg.hpp"
#include "libcvo/image/png.hpp"
#include "libcvo/image/webp.hpp"
#include "libcvo/lcm/rgbd_conversion.hpp"

namespace {

using namespace cvo;
using Bytes = std::vector<std::uint8_t>;

const std::string kSample = CVO_TEST_DATA_DIR "/fr1_rpy_50/";

Bytes file_bytes(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open " + file);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Frame 0 of the sample, as the daemons see it.
const Bytes& colour_webp() {
  static const Bytes bytes = file_bytes(kSample + "rgb/1305031229.528748.webp");
  return bytes;
}
const cv::Mat& colour() {
  static const cv::Mat bgr = cv::imdecode(colour_webp(), cv::IMREAD_COLOR);
  return bgr;
}
const cv::Mat& depth() {
  static const cv::Mat d = cv::imread(kSample + "depth/1305031229.528784.png", cv::IMREAD_UNCHANGED);
  return d;
}

const int kJpegQuality = lcm::RgbdEncoding{}.jpeg_quality;
const int kPngCompression = lcm::RgbdEncoding{}.png_compression;

void check(const std::string& error, benchmark::State& state) {
  if (!error.empty()) state.SkipWithError(error.c_str());
}

// --- encode ---

void BM_EncodeColourPng_Ours(benchmark::State& state) {
  Bytes out;
  for (auto _ : state) check(image::encode_png(colour(), image::PngPixels::kBgr8, kPngCompression, out), state);
  state.counters["bytes"] = double(out.size());
}
void BM_EncodeColourPng_OpenCv(benchmark::State& state) {
  Bytes out;
  for (auto _ : state) cv::imencode(".png", colour(), out, {cv::IMWRITE_PNG_COMPRESSION, kPngCompression});
  state.counters["bytes"] = double(out.size());
}
void BM_EncodeColourJpeg_Ours(benchmark::State& state) {
  Bytes out;
  for (auto _ : state) check(image::encode_jpeg(colour(), kJpegQuality, out), state);
  state.counters["bytes"] = double(out.size());
}
void BM_EncodeColourJpeg_OpenCv(benchmark::State& state) {
  Bytes out;
  for (auto _ : state) cv::imencode(".jpg", colour(), out, {cv::IMWRITE_JPEG_QUALITY, kJpegQuality});
  state.counters["bytes"] = double(out.size());
}
void BM_EncodeDepthPng_Ours(benchmark::State& state) {
  Bytes out;
  for (auto _ : state) check(image::encode_png(depth(), image::PngPixels::kGrey16, kPngCompression, out), state);
  state.counters["bytes"] = double(out.size());
}
void BM_EncodeDepthPng_OpenCv(benchmark::State& state) {
  Bytes out;
  for (auto _ : state) cv::imencode(".png", depth(), out, {cv::IMWRITE_PNG_COMPRESSION, kPngCompression});
  state.counters["bytes"] = double(out.size());
}

// --- decode: each side decodes the same bytes, OpenCV's encoding of the frame ---

Bytes opencv_encoded(const char* ext, const cv::Mat& image, const std::vector<int>& params) {
  Bytes out;
  cv::imencode(ext, image, out, params);
  return out;
}
const Bytes& colour_png() {
  static const Bytes b = opencv_encoded(".png", colour(), {cv::IMWRITE_PNG_COMPRESSION, kPngCompression});
  return b;
}
const Bytes& colour_jpeg() {
  static const Bytes b = opencv_encoded(".jpg", colour(), {cv::IMWRITE_JPEG_QUALITY, kJpegQuality});
  return b;
}
const Bytes& depth_png() {
  static const Bytes b = opencv_encoded(".png", depth(), {cv::IMWRITE_PNG_COMPRESSION, kPngCompression});
  return b;
}

// Ours decodes into an image of the frame's size, as the readers of fixed-size frames do.
void BM_DecodeColourPng_Ours(benchmark::State& state) {
  cv::Mat out(480, 640, CV_8UC3);
  for (auto _ : state) check(image::decode_png(colour_png(), image::PngPixels::kBgr8, out, {640, 480}), state);
}
void BM_DecodeColourPng_OpenCv(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(cv::imdecode(colour_png(), cv::IMREAD_COLOR).data);
}
void BM_DecodeColourJpeg_Ours(benchmark::State& state) {
  cv::Mat out(480, 640, CV_8UC3);
  for (auto _ : state) check(image::decode_jpeg(colour_jpeg(), out, {640, 480}), state);
}
void BM_DecodeColourJpeg_OpenCv(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(cv::imdecode(colour_jpeg(), cv::IMREAD_COLOR).data);
}
void BM_DecodeDepthPng_Ours(benchmark::State& state) {
  cv::Mat out(480, 640, CV_16UC1);
  for (auto _ : state) check(image::decode_png(depth_png(), image::PngPixels::kGrey16, out, {640, 480}), state);
}
void BM_DecodeDepthPng_OpenCv(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(cv::imdecode(depth_png(), cv::IMREAD_UNCHANGED).data);
}
void BM_DecodeColourWebp_Ours(benchmark::State& state) {
  cv::Mat out(480, 640, CV_8UC3);
  for (auto _ : state) check(image::decode_webp(colour_webp(), out, {640, 480}), state);
}
void BM_DecodeColourWebp_OpenCv(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(cv::imdecode(colour_webp(), cv::IMREAD_COLOR).data);
}

BENCHMARK(BM_EncodeColourPng_Ours)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EncodeColourPng_OpenCv)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EncodeColourJpeg_Ours)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EncodeColourJpeg_OpenCv)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EncodeDepthPng_Ours)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EncodeDepthPng_OpenCv)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DecodeColourPng_Ours)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DecodeColourPng_OpenCv)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DecodeColourJpeg_Ours)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DecodeColourJpeg_OpenCv)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DecodeDepthPng_Ours)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DecodeDepthPng_OpenCv)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DecodeColourWebp_Ours)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DecodeColourWebp_OpenCv)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
