// CVO_RGBD as cvo-trackerd and the lcm: frame source receive it: decode, then from_message, which
// checks the JPEG/PNG headers and runs the declared image decoder (the expensive, risky part).
#include <opencv2/core.hpp>

#include "cvo_lcm/rgbd_frame_t.hpp"
#include "fuzz/lcm_harness.hpp"
#include "libcvo/lcm/rgbd_conversion.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cvo::fuzz::fuzz_message<cvo_lcm::rgbd_frame_t>(data, size, [](const cvo_lcm::rgbd_frame_t& message) {
    std::string error;
    cvo::core::BadKind kind{};
    const auto frame = cvo::lcm::from_message(message, &error, &kind);
    if (!frame) return;
    // from_message's promise: images of the message's size and the tracker's types.
    const cv::Size image_size(message.width, message.height);
    if (frame->bgr.type() != CV_8UC3 || frame->depth.type() != CV_16UC1 || frame->bgr.size() != image_size ||
        frame->depth.size() != image_size) {
      cvo::fuzz::fail("from_message accepted a frame whose images are not the message's size and type");
    }
  });
  return 0;
}
