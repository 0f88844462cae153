// A TUM folder's index: rgb.txt, depth.txt and groundtruth.txt, given as the input's parts
// separated by lines "---" (one part: rgb.txt and depth.txt alike; no third part: no ground
// truth), opened with TumSequence::open. The camera is given, so no image is opened: the lists,
// their association and the ground truth are what is fuzzed.
#include "fuzz/harness.hpp"
#include "libcvo/core/camera.hpp"
#include "libcvo/io/tum_dataset.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto parts = cvo::fuzz::split_parts(cvo::fuzz::as_text(data, size));
  const auto& dir = cvo::fuzz::scratch_dir();
  cvo::fuzz::write_file(dir / "rgb.txt", parts[0]);
  cvo::fuzz::write_file(dir / "depth.txt", parts.size() > 1 ? parts[1] : parts[0]);
  if (parts.size() > 2) cvo::fuzz::write_file(dir / "groundtruth.txt", parts[2]);
  cvo::io::TumOptions options;
  options.intrinsics = cvo::core::camera_preset("tum_fr1");
  cvo::fuzz::expect_refusal_or_success([&] { (void)cvo::io::TumSequence::open(dir, options); });
  return 0;
}
