// The vocabulary tree: descriptors, the L1 score, training (k-medians, TF-IDF) and transform().
#include "libcvo/loop_closure/vocabulary.hpp"

#include <cmath>
#include <cstdint>
#include <numeric>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "loop_closure/test_images.hpp"

namespace cvo::loop_closure {
namespace {

// A descriptor matrix from 32-byte rows given by a byte pattern each.
cv::Mat rows(const std::vector<unsigned char>& fills) {
  cv::Mat m(static_cast<int>(fills.size()), 32, CV_8UC1);
  for (int r = 0; r < m.rows; ++r) m.row(r).setTo(fills[static_cast<std::size_t>(r)]);
  return m;
}

// n random descriptors, each `flips` random bits away from one of the given prototypes.
cv::Mat noisy_copies(const std::vector<Descriptor>& prototypes, int n, int flips, cv::RNG& rng) {
  cv::Mat m(n, 32, CV_8UC1);
  for (int r = 0; r < n; ++r) {
    Descriptor d = prototypes[static_cast<std::size_t>(rng.uniform(0, static_cast<int>(prototypes.size())))];
    for (int f = 0; f < flips; ++f) {
      const int bit = rng.uniform(0, 256);
      d[static_cast<std::size_t>(bit / 64)] ^= std::uint64_t{1} << (bit % 64);
    }
    std::memcpy(m.ptr(r), d.data(), 32);
  }
  return m;
}

double sum(const BowVector& v) {
  return std::accumulate(v.begin(), v.end(), 0.0, [](double s, const BowEntry& e) { return s + e.weight; });
}

TEST(Descriptors, HammingCountsDifferingBitsOfTheRows) {
  const auto d = to_descriptors(rows({0x00, 0xff, 0x0f}));
  ASSERT_EQ(d.size(), 3u);
  EXPECT_EQ(hamming(d[0], d[0]), 0);
  EXPECT_EQ(hamming(d[0], d[1]), 256);
  EXPECT_EQ(hamming(d[0], d[2]), 128);
  EXPECT_EQ(hamming(d[1], d[2]), 128);
  EXPECT_TRUE(to_descriptors(cv::Mat()).empty());
  EXPECT_THROW(to_descriptors(cv::Mat(2, 16, CV_8UC1)), std::invalid_argument);
  EXPECT_THROW(to_descriptors(cv::Mat(2, 32, CV_32FC1)), std::invalid_argument);
}

TEST(Score, IsOneMinusHalfTheL1Distance) {
  const BowVector a{{1, 0.5}, {2, 0.25}, {7, 0.25}};
  const BowVector b{{2, 0.5}, {3, 0.25}, {7, 0.25}};
  // |a - b|_1 = 0.5 + 0.25 + 0.25 + 0 = 1, so s = 0.5.
  EXPECT_DOUBLE_EQ(score(a, b), 0.5);
  EXPECT_DOUBLE_EQ(score(b, a), 0.5);
  EXPECT_DOUBLE_EQ(score(a, a), 1.0);
  EXPECT_DOUBLE_EQ(score(a, BowVector{{4, 1.0}}), 0.0);  // no common word
  EXPECT_DOUBLE_EQ(score(a, BowVector{}), 0.0);          // no words at all
  EXPECT_DOUBLE_EQ(score(BowVector{}, BowVector{}), 0.0);
}

TEST(Vocabulary, IdfIsLogOfImagesOverImagesWithTheWordAndTransformIsL1Normalised) {
  // Three far-apart descriptors; k = 3, L = 1: one word each. Image 0 {A}, 1 {A, B, B}, 2 {C, A}.
  const auto voc =
      Vocabulary::train({rows({0x00}), rows({0x00, 0xff, 0xff}), rows({0x0f, 0x00})}, {.branching = 3, .levels = 1});
  ASSERT_EQ(voc.words(), 3u);
  EXPECT_EQ(voc.training_images(), 3u);
  const auto d = to_descriptors(rows({0x00, 0xff, 0x0f}));
  const WordId a = voc.word(d[0]), b = voc.word(d[1]), c = voc.word(d[2]);
  EXPECT_NE(a, b);
  EXPECT_NE(b, c);
  EXPECT_NE(a, c);
  EXPECT_DOUBLE_EQ(voc.idf(a), 0.0);  // in every image
  EXPECT_DOUBLE_EQ(voc.idf(b), std::log(3.0));
  EXPECT_DOUBLE_EQ(voc.idf(c), std::log(3.0));

  // tf-idf: B twice, C once, A dropped (idf 0): weights 2/3 and 1/3.
  const BowVector v = voc.transform(rows({0xff, 0x00, 0x0f, 0xff}));
  ASSERT_EQ(v.size(), 2u);
  const BowEntry& first = v[0].word == b ? v[0] : v[1];
  const BowEntry& second = v[0].word == b ? v[1] : v[0];
  EXPECT_EQ(first.word, b);
  EXPECT_EQ(second.word, c);
  EXPECT_DOUBLE_EQ(first.weight, 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(second.weight, 1.0 / 3.0);
  EXPECT_LT(v[0].word, v[1].word);
  EXPECT_TRUE(voc.transform(rows({0x00, 0x00})).empty());  // only the word of every image
  EXPECT_TRUE(voc.transform(cv::Mat()).empty());
}

TEST(Vocabulary, TreeHasAtMostKChildrenPerNodeAndWordsNoDeeperThanL) {
  cv::RNG rng(7);
  std::vector<Descriptor> prototypes(40);
  for (auto& p : prototypes)
    for (auto& block : p) block = (std::uint64_t{rng.next()} << 32) | rng.next();
  std::vector<cv::Mat> images;
  for (int i = 0; i < 8; ++i) images.push_back(noisy_copies(prototypes, 300, 20, rng));
  const auto voc = Vocabulary::train(images, {.branching = 4, .levels = 3, .seed = 1});
  const auto& nodes = voc.nodes();
  std::vector<int> children(nodes.size(), 0), depth(nodes.size(), 0);
  for (std::size_t i = 1; i < nodes.size(); ++i) {
    ASSERT_LT(nodes[i].parent, i);
    ++children[nodes[i].parent];
    depth[i] = depth[nodes[i].parent] + 1;
  }
  std::size_t leaves = 0;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    EXPECT_LE(children[i], 4);
    EXPECT_LE(depth[i], 3);
    leaves += children[i] == 0;
  }
  EXPECT_EQ(voc.words(), leaves);
  EXPECT_GT(voc.words(), 16u);  // 40 clusters in the data: the tree uses its depth
  EXPECT_LE(voc.words(), 64u);

  const BowVector v = voc.transform(images[0]);
  EXPECT_NEAR(sum(v), 1.0, 1e-12);
  for (std::size_t e = 1; e < v.size(); ++e) EXPECT_LT(v[e - 1].word, v[e].word);
}

TEST(Vocabulary, CentresAreBitwiseMajoritiesOfTheirMembers) {
  // Nine descriptors in three tight groups of three: k = 3, L = 2 splits them into the groups,
  // and each group's centre is its majority (two of three rows agree on every byte here).
  const auto voc =
      Vocabulary::train({rows({0x01, 0x03, 0x01, 0xf0, 0xf8, 0xf0, 0x3c, 0x3c, 0x7c})}, {.branching = 3, .levels = 2});
  std::vector<Descriptor> level1;
  for (const auto& n : voc.nodes())
    if (n.parent == 0) level1.push_back(n.centre);
  ASSERT_EQ(level1.size(), 3u);
  for (const unsigned char expected : {0x01, 0xf0, 0x3c}) {
    const Descriptor want = to_descriptors(rows({expected}))[0];
    EXPECT_NE(std::find(level1.begin(), level1.end(), want), level1.end()) << int{expected};
  }
}

TEST(Vocabulary, TrainingIsDeterministicGivenTheSeed) {
  cv::RNG rng(3);
  std::vector<Descriptor> prototypes(30);
  for (auto& p : prototypes)
    for (auto& block : p) block = (std::uint64_t{rng.next()} << 32) | rng.next();
  std::vector<cv::Mat> images;
  for (int i = 0; i < 4; ++i) images.push_back(noisy_copies(prototypes, 400, 30, rng));
  const auto a = Vocabulary::train(images, {.branching = 5, .levels = 3, .seed = 11});
  const auto b = Vocabulary::train(images, {.branching = 5, .levels = 3, .seed = 11});
  const auto c = Vocabulary::train(images, {.branching = 5, .levels = 3, .seed = 12});
  EXPECT_TRUE(a == b);
  EXPECT_EQ(a.checksum(), b.checksum());
  EXPECT_FALSE(a == c);  // another seed, other k-means++ seeds
}

TEST(Vocabulary, RejectsBadParametersAndEmptyTrainingSets) {
  const std::vector<cv::Mat> one{rows({0x00, 0xff})};
  EXPECT_THROW(Vocabulary::train(one, {.branching = 1}), std::invalid_argument);
  EXPECT_THROW(Vocabulary::train(one, {.branching = 257}), std::invalid_argument);
  EXPECT_THROW(Vocabulary::train(one, {.levels = 0}), std::invalid_argument);
  EXPECT_THROW(Vocabulary::train(one, {.levels = 17}), std::invalid_argument);
  EXPECT_THROW(Vocabulary::train({}, {}), std::invalid_argument);
  EXPECT_THROW(Vocabulary::train({cv::Mat()}, {}), std::invalid_argument);
  EXPECT_THROW(Vocabulary::train({cv::Mat(3, 32, CV_32FC1)}, {}), std::invalid_argument);
}

// Two image families: real office frames (fr1/rpy) and the rendered textured room. A vocabulary
// trained on both must score images of one family higher with each other than across families.
TEST(Vocabulary, ScoresWithinAnImageFamilyAboveAcrossFamilies) {
  std::vector<cv::Mat> office, room;
  for (std::size_t i = 0; i < 50; i += 7) office.push_back(testing::orb(testing::sample_frame(i)));  // 8 frames
  for (double t = 0; t < 1.0; t += 0.125) room.push_back(testing::orb(testing::room_frame(t)));      // 8 frames
  std::vector<cv::Mat> training;
  for (std::size_t i = 0; i < office.size(); i += 2) training.push_back(office[i]);  // half of each family;
  for (std::size_t i = 0; i < room.size(); i += 2) training.push_back(room[i]);      // the rest is unseen
  const auto voc = Vocabulary::train(training, {.branching = 8, .levels = 3, .seed = 5});

  std::vector<BowVector> a, b;
  for (const auto& d : office) a.push_back(voc.transform(d));
  for (const auto& d : room) b.push_back(voc.transform(d));
  double within = 0, across = 0, max_across = 0;
  int n_within = 0, n_across = 0;
  for (const auto* family : {&a, &b})
    for (std::size_t i = 0; i < family->size(); ++i)
      for (std::size_t j = i + 1; j < family->size(); ++j) within += score((*family)[i], (*family)[j]), ++n_within;
  for (const auto& x : a)
    for (const auto& y : b) {
      const double s = score(x, y);
      across += s, ++n_across, max_across = std::max(max_across, s);
    }
  within /= n_within;
  across /= n_across;
  // Seen here: 0.53 within, 0.27 across (k 8, L 3: few words, so unrelated images share some).
  EXPECT_GT(within, 1.5 * across) << "mean within " << within << ", across " << across;
  // Every image is closer to its own family's best match than to any image of the other family.
  for (const auto* family : {&a, &b})
    for (std::size_t i = 0; i < family->size(); ++i) {
      double best = 0;
      for (std::size_t j = 0; j < family->size(); ++j)
        if (j != i) best = std::max(best, score((*family)[i], (*family)[j]));
      EXPECT_GT(best, max_across) << "image " << i;
    }
}

}  // namespace
}  // namespace cvo::loop_closure
