// The receiver's door: messages are named by (session, keyframe id) from their encoding alone; a
// name is let in once; the same bytes again are a repeat, other bytes a conflict.
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "cvo_lcm/status_t.hpp"
#include "daemon/backendd/message_door.hpp"
#include "tests/lcm/sample_messages.hpp"

namespace cvo::daemon::backendd {
namespace {

template <class T>
std::vector<std::uint8_t> encoded(const T& message) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

std::uint32_t crc(const std::vector<std::uint8_t>& bytes) { return crc32_of(bytes.data(), bytes.size()); }

TEST(MessageDoor, NamesMessagesBySessionAndKeyframeId) {
  const auto keyframe = cvo::test::sample_keyframe();
  const auto k = encoded(keyframe);
  const auto key = identify(RecordKind::kKeyframe, k.data(), k.size(), nullptr, nullptr);
  ASSERT_TRUE(key);
  EXPECT_EQ(*key, (MessageKey{RecordKind::kKeyframe, keyframe.session, keyframe.id}));

  const auto graph = cvo::test::sample_local_graph();
  const auto g = encoded(graph);
  const auto graph_key = identify(RecordKind::kLocalGraph, g.data(), g.size(), nullptr, nullptr);
  ASSERT_TRUE(graph_key);
  EXPECT_EQ(*graph_key, (MessageKey{RecordKind::kLocalGraph, graph.session, graph.keyframe_id}));
  EXPECT_EQ(describe(*graph_key), "the local graph of keyframe 5 of session 0x005e551000000001");

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

TEST(MessageDoor, ContentIsCheckedAsTheBackEndWillUseIt) {
  const auto graph = encoded(cvo::test::sample_local_graph());
  std::string error;
  std::size_t bad = 0;
  EXPECT_TRUE(usable(RecordKind::kLocalGraph, graph.data(), graph.size(), &error, &bad)) << error;
  const auto keyframe = encoded(cvo::test::sample_keyframe());  // its "JPEG" is a few bytes of header
  EXPECT_FALSE(usable(RecordKind::kKeyframe, keyframe.data(), keyframe.size(), &error, &bad));
  EXPECT_FALSE(error.empty());
  EXPECT_EQ(bad, +cvo_lcm::status_t::BAD_IMAGE_FORMAT) << "no frame header: refused before a decoder runs";
  auto indefinite = cvo::test::sample_local_graph();
  indefinite.edges[1].information[7] = -3.0;  // a negative variance
  const auto bytes = encoded(indefinite);
  EXPECT_FALSE(usable(RecordKind::kLocalGraph, bytes.data(), bytes.size(), &error, &bad));
  EXPECT_EQ(bad, +cvo_lcm::status_t::BAD_INFORMATION) << error;
}

}  // namespace
}  // namespace cvo::daemon::backendd
