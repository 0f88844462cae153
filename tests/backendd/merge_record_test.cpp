// The store's merge and settled records (libcvo/store/merge_record.hpp): what is written reads back whole,
// and bytes that are not one are refused with a reason.
#include <gtest/gtest.h>

#include "libcvo/store/merge_record.hpp"

namespace cvo::store {
namespace {

slam::KeyframeMerge sample_merge() {
  slam::KeyframeMerge m;
  m.session = 2;
  m.id = 7;
  m.frame = 31;
  m.timestamp = 1305031229.5;
  m.odometry = core::SE3::exp((core::Vector6d() << 0.1, -0.2, 0.3, 0.01, 0.02, -0.03).finished());
  m.covering_session = 1;
  m.covering_id = 5;
  m.relative = core::SE3::exp((core::Vector6d() << 0.01, 0.02, 0.0, 0.001, 0.0, 0.002).finished());
  m.information = 250.0 * core::Matrix6d::Identity();
  m.gamma = 0.83;
  loop_closure::LoopClosure loop;
  loop.from = 12;
  loop.to = (std::int64_t{1} << 40) | 31;
  loop.eta = 0.6;
  loop.alpha = 0.01;
  loop.inliers = 40;
  m.others.push_back(loop);
  return m;
}

TEST(MergeRecord, WhatIsWrittenReadsBackWhole) {
  const auto m = sample_merge();
  const auto bytes = encode_merge(m);
  std::string error;
  const auto back = decode_merge(bytes.data(), bytes.size(), &error);
  ASSERT_TRUE(back) << error;
  EXPECT_EQ(back->session, m.session);
  EXPECT_EQ(back->id, m.id);
  EXPECT_EQ(back->frame, m.frame);
  EXPECT_EQ(back->timestamp, m.timestamp);
  EXPECT_EQ(back->covering_id, m.covering_id);
  EXPECT_TRUE(back->relative.translation().isApprox(m.relative.translation()));
  EXPECT_TRUE(back->information.isApprox(m.information));
  EXPECT_TRUE(back->joining.empty());
  ASSERT_EQ(back->others.size(), 1u);
  EXPECT_EQ(back->others[0].to, m.others[0].to);
  EXPECT_EQ(back->others[0].inliers, 40);
  EXPECT_EQ(encode_merge(*back), bytes);  // the same input writes the same bytes
}

TEST(MergeRecord, BytesThatAreNotOneAreRefused) {
  const auto bytes = encode_merge(sample_merge());
  std::string error;
  EXPECT_FALSE(decode_merge(bytes.data(), bytes.size() - 1, &error));
  EXPECT_NE(error.find("cut short"), std::string::npos) << error;
  auto longer = bytes;
  longer.push_back(0);
  EXPECT_FALSE(decode_merge(longer.data(), longer.size(), &error));
  auto other_version = bytes;
  other_version[0] = 9;
  EXPECT_FALSE(decode_merge(other_version.data(), other_version.size(), &error));
  EXPECT_NE(error.find("version"), std::string::npos) << error;
}

TEST(SettledRecord, WhatIsWrittenReadsBackWholeAndOtherBytesAreRefused) {
  slam::SettledEdge e;
  e.from_session = 3;
  e.from_id = 4;
  e.to_session = 1;
  e.to_id = 9;
  e.robust = true;
  e.measurement = core::SE3::exp((core::Vector6d() << 0.2, 0.0, -0.1, 0.0, 0.03, 0.0).finished());
  e.information = 1e4 * core::Matrix6d::Identity();
  const auto bytes = encode_settled(e);
  std::string error;
  const auto back = decode_settled(bytes.data(), bytes.size(), &error);
  ASSERT_TRUE(back) << error;
  EXPECT_EQ(back->from_id, 4);
  EXPECT_EQ(back->to_session, 1);
  EXPECT_TRUE(back->robust);
  EXPECT_TRUE(back->information.isApprox(e.information));
  EXPECT_EQ(encode_settled(*back), bytes);
  EXPECT_FALSE(decode_settled(bytes.data(), bytes.size() - 1, &error));
  EXPECT_NE(error.find("cut short"), std::string::npos) << error;
  auto flag = bytes;
  flag[1 + 4 * 8] = 2;  // the robust flag
  EXPECT_FALSE(decode_settled(flag.data(), flag.size(), &error));
  auto other_version = bytes;
  other_version[0] = 9;
  EXPECT_FALSE(decode_settled(other_version.data(), other_version.size(), &error));
  EXPECT_NE(error.find("version"), std::string::npos) << error;
}

TEST(TallyRecord, WhatIsWrittenReadsBackWholeAndOtherBytesAreRefused) {
  const slam::SessionTally t{5, 42, 117};
  const auto bytes = encode_tally(t);
  std::string error;
  const auto back = decode_tally(bytes.data(), bytes.size(), &error);
  ASSERT_TRUE(back) << error;
  EXPECT_EQ(back->session, 5);
  EXPECT_EQ(back->forgotten, 42u);
  EXPECT_EQ(back->settled_through, 117);
  EXPECT_FALSE(decode_tally(bytes.data(), bytes.size() - 1, &error));
  EXPECT_NE(error.find("cut short"), std::string::npos) << error;
  auto longer = bytes;
  longer.push_back(1);
  EXPECT_FALSE(decode_tally(longer.data(), longer.size(), &error));
}

}  // namespace
}  // namespace cvo::store
