// The receiver's door: messages are named by (session, keyframe id) from their encoding alone; a
// name is let in once; the same bytes again are a repeat, other bytes a conflict. A message is
// decoded once: identify() gives the decoded message, usable() the value the back end applies.
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cvo_lcm/status_t.hpp"
#include "libcvo/store/message_door.hpp"
#include "tests/lcm/sample_messages.hpp"

namespace cvo::store {
namespace {

template <class T>
std::vector<std::uint8_t> encoded(const T& message) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

std::uint32_t crc(const std::vector<std::uint8_t>& bytes) { return crc32_of(bytes.data(), bytes.size()); }

// A keyframe sent again on request is signed afresh (a new counter in its auth_t trailer): the door
// compares what it says, not who signed it when, so the re-send is a repeat, not a conflict.
TEST(MessageDoor, ComparesContentWithoutTheAuthTrailer) {
  auto keyframe = test::sample_keyframe();
  const auto first = lcm::encode(keyframe);
  keyframe.auth.counter = 12345;
  keyframe.auth.authenticator[7] = 9;
  const auto resent = lcm::encode(keyframe);
  ASSERT_NE(first, resent);
  EXPECT_EQ(content_crc(first.data(), first.size()), content_crc(resent.data(), resent.size()));
  keyframe.id += 1;
  const auto other = lcm::encode(keyframe);
  EXPECT_NE(content_crc(first.data(), first.size()), content_crc(other.data(), other.size()));
}

TEST(MessageDoor, NamesMessagesBySessionAndKeyframeId) {
  const auto keyframe = cvo::test::sample_keyframe();
  const auto k = encoded(keyframe);
  const auto key = identify(RecordKind::kKeyframe, k.data(), k.size(), nullptr, nullptr);
  ASSERT_TRUE(key);
  EXPECT_EQ(key->key, (MessageKey{RecordKind::kKeyframe, keyframe.session, keyframe.id}));

  const auto graph = cvo::test::sample_local_graph();
  const auto g = encoded(graph);
  const auto graph_key = identify(RecordKind::kLocalGraph, g.data(), g.size(), nullptr, nullptr);
  ASSERT_TRUE(graph_key);
  EXPECT_EQ(graph_key->key, (MessageKey{RecordKind::kLocalGraph, graph.session, graph.keyframe_id}));
  EXPECT_EQ(describe(graph_key->key), "the local graph of keyframe 5 of session 0x005e551000000001");

  // A local graph's bytes on the keyframe channel: another type, counted as such.
  std::string error;
  std::size_t bad = 99;
  EXPECT_FALSE(identify(RecordKind::kKeyframe, g.data(), g.size(), &error, &bad));
  EXPECT_EQ(bad, +cvo_lcm::status_t::BAD_FINGERPRINT) << error;
  EXPECT_FALSE(identify(RecordKind::kKeyframe, k.data(), 5, &error, &bad));
  EXPECT_EQ(bad, +cvo_lcm::status_t::BAD_TOO_SHORT) << error;
}

TEST(MessageDoor, ANameIsLetInOnceAndOtherContentUnderItIsAConflict) {
  auto keyframe = cvo::test::sample_keyframe();
  const auto first = encoded(keyframe);
  const MessageKey key{RecordKind::kKeyframe, keyframe.session, keyframe.id};
  MessageDoor door;
  EXPECT_EQ(door.check(key, crc(first)), Admission::kNew);
  door.admit(key, crc(first));
  EXPECT_EQ(door.check(key, crc(first)), Admission::kRepeat);

  keyframe.pose.position[0] += 0.01;  // the same keyframe, re-sent with another pose
  const auto other = encoded(keyframe);
  EXPECT_EQ(door.check(key, crc(other)), Admission::kConflict);
  door.admit(key, crc(other));  // the first content stays the reference
  EXPECT_EQ(door.check(key, crc(first)), Admission::kRepeat);

  // The same id in another session, and the keyframe's local graph, are other names.
  EXPECT_EQ(door.check({RecordKind::kKeyframe, keyframe.session + 1, keyframe.id}, crc(other)), Admission::kNew);
  EXPECT_EQ(door.check({RecordKind::kLocalGraph, keyframe.session, keyframe.id}, crc(other)), Admission::kNew);
  EXPECT_EQ(door.size(), 1u);
}

// What identify() decoded, usable() checks as the back end will use it.
std::optional<RecordValue> value(RecordKind kind, const std::vector<std::uint8_t>& bytes, std::string* error,
                                 std::size_t* bad) {
  const auto message = identify(kind, bytes.data(), bytes.size(), error, bad);
  EXPECT_TRUE(message) << *error;
  return message ? usable(*message, error, bad) : std::nullopt;
}

TEST(MessageDoor, ContentIsCheckedAsTheBackEndWillUseIt) {
  const auto graph = encoded(cvo::test::sample_local_graph());
  std::string error;
  std::size_t bad = 0;
  EXPECT_TRUE(value(RecordKind::kLocalGraph, graph, &error, &bad)) << error;
  const auto keyframe = encoded(cvo::test::sample_keyframe());  // its "JPEG" is a few bytes of header
  EXPECT_FALSE(value(RecordKind::kKeyframe, keyframe, &error, &bad));
  EXPECT_FALSE(error.empty());
  EXPECT_EQ(bad, +cvo_lcm::status_t::BAD_IMAGE_FORMAT) << "no frame header: refused before a decoder runs";
  auto indefinite = cvo::test::sample_local_graph();
  indefinite.edges[1].information[7] = -3.0;  // a negative variance
  EXPECT_FALSE(value(RecordKind::kLocalGraph, encoded(indefinite), &error, &bad));
  EXPECT_EQ(bad, +cvo_lcm::status_t::BAD_INFORMATION) << error;
}

// The value is what the back end applies: the keyframe with its images decoded, the graph of its
// keyframe; nothing is left to decode after the door.
TEST(MessageDoor, AUsableMessageGivesTheValueTheBackEndApplies) {
  auto keyframe = cvo::test::sample_keyframe();
  const cv::Mat bgr(keyframe.height, keyframe.width, CV_8UC3, cv::Scalar(1, 2, 3));
  cv::imencode(".png", bgr, keyframe.colour);
  keyframe.colour_encoding = cvo_lcm::rgbd_frame_t::COLOUR_PNG;
  keyframe.colour_size = static_cast<std::int32_t>(keyframe.colour.size());
  cv::imencode(".png", cv::Mat(keyframe.height, keyframe.width, CV_16UC1, cv::Scalar(5000)), keyframe.depth);
  keyframe.depth_size = static_cast<std::int32_t>(keyframe.depth.size());
  std::string error;
  std::size_t bad = 0;
  const auto k = value(RecordKind::kKeyframe, encoded(keyframe), &error, &bad);
  ASSERT_TRUE(k) << error;
  const auto* decoded = std::get_if<lcm::Keyframe>(&*k);
  ASSERT_NE(decoded, nullptr);
  EXPECT_EQ(decoded->session, keyframe.session);
  EXPECT_EQ(decoded->id, keyframe.id);
  EXPECT_EQ(cv::norm(decoded->frame.bgr, bgr, cv::NORM_INF), 0) << "the images are decoded";
  EXPECT_EQ(decoded->cloud.size(), static_cast<std::size_t>(keyframe.num_points));

  const auto graph = cvo::test::sample_local_graph();
  const auto g = value(RecordKind::kLocalGraph, encoded(graph), &error, &bad);
  ASSERT_TRUE(g) << error;
  const auto* local = std::get_if<LocalGraphRecord>(&*g);
  ASSERT_NE(local, nullptr);
  EXPECT_EQ(local->session, graph.session);
  EXPECT_EQ(local->keyframe_id, graph.keyframe_id);
  EXPECT_EQ(local->graph.nodes().size(), graph.nodes.size());
}

}  // namespace
}  // namespace cvo::store
