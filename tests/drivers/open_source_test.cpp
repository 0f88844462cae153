// open_source(): the --source contract of cvo-trackerd. A spec it cannot understand is an error
// that lists the valid ones; each scheme reaches its own source.
#include <gtest/gtest.h>

#include "drivers/frame_source.hpp"
#include "drivers/open_source.hpp"

namespace cvo::drivers {
namespace {

std::string open_error(const std::string& spec) {
  try {
    open_source(spec);
  } catch (const SourceError& e) {
    return e.what();
  }
  ADD_FAILURE() << spec << " opened";
  return {};
}

TEST(OpenSource, UnknownSchemeListsTheValidOnes) {
  for (const std::string spec : {"rtsp://camera", "", "/data/fr1_desk", "TUM:/data"}) {
    const auto error = open_error(spec);
    for (const char* scheme : {"tum:DIR", "lcm:URL", "openni2:URI", "v4l2:COLOUR,DEPTH"})
      EXPECT_NE(error.find(scheme), std::string::npos) << spec << ": " << error;
  }
}

TEST(OpenSource, EachSchemeReachesItsSource) {
  EXPECT_NE(open_error("tum:/no/such/fr1_folder").find("/no/such/fr1_folder"), std::string::npos);
  EXPECT_NE(open_error("lcm:file:///no/such/log.lcm").find("LCM"), std::string::npos);
  EXPECT_NE(open_error("v4l2:/dev/a,/dev/b").find("intrinsics"), std::string::npos);
}

TEST(OpenSource, StatusNames) {
  EXPECT_STREQ(to_string(ReadStatus::kEndOfStream), "end of stream");
  EXPECT_STREQ(to_string(ReadStatus::kDisconnected), "disconnected");
  EXPECT_STREQ(to_string(core::BadKind::kFingerprint), "fingerprint");
  EXPECT_STREQ(to_string(core::BadKind::kContent), "content");
}

}  // namespace
}  // namespace cvo::drivers
