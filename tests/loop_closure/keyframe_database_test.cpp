// Loop-closure candidates by the normalised score η = s(v_i, v_j) / s(v_i, v_{i-1}).
#include "libcvo/loop_closure/keyframe_database.hpp"

#include <algorithm>
#include <numeric>
#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace cvo::loop_closure {
namespace {

std::vector<KeyframeId> ids_of(const std::vector<LoopCandidate>& c) {
  std::vector<KeyframeId> ids;
  for (const auto& x : c) ids.push_back(x.id);
  return ids;
}

// Dyadic weights keep every score exact. With the query q = {1: .5, 2: .25, 3: .25}:
//   s(q, previous)  = 0.5  (words 1)
//   s(q, kf 10)     = 0.25 -> η 0.5
//   s(q, kf 11)     = 0.125 -> η 0.25
//   s(q, kf 12)     = 0.375 -> η 0.75
//   s(q, kf 13)     = 0 (no common word)
//   s(q, kf 14)     = 0.15625 -> η 0.3125
const BowVector kQuery{{1, 0.5}, {2, 0.25}, {3, 0.25}};

KeyframeDatabase example() {
  KeyframeDatabase db;
  db.add(10, {{2, 0.25}, {9, 0.75}});
  db.add(11, {{3, 0.125}, {8, 0.875}});
  db.add(12, {{2, 0.25}, {3, 0.125}, {9, 0.625}});
  db.add(13, {{4, 1.0}});
  db.add(14, {{2, 0.15625}, {9, 0.84375}});
  db.add(20, {{1, 0.5}, {7, 0.5}});  // the previous keyframe
  return db;
}

TEST(KeyframeDatabase, ARemovedKeyframeIsNoCandidateAndTheOthersScoreAsBefore) {
  KeyframeDatabase db = example();
  db.remove(12);
  EXPECT_FALSE(db.contains(12));
  EXPECT_EQ(db.size(), 5u);
  EXPECT_EQ(ids_of(db.candidates(21, kQuery, 20, 0.3)), (std::vector<KeyframeId>{10, 14}));
  EXPECT_THROW(db.remove(12), std::out_of_range);
  db.add(12, {{1, 0.5}, {2, 0.5}});  // an id may come back
  EXPECT_EQ(ids_of(db.candidates(21, kQuery, 20, 0.3)), (std::vector<KeyframeId>{12, 10, 14}));
}

TEST(KeyframeDatabase, AWindowOfKeyframesHoldsBoundedMemoryAsItMovesOn) {
  KeyframeDatabase db;
  for (KeyframeId id = 0; id < 1000; ++id) {
    db.add(id, {{static_cast<std::uint32_t>(id % 50), 0.5}, {60, 0.5}});
    if (id >= 8) db.remove(id - 8);
  }
  EXPECT_EQ(db.size(), 8u);
  EXPECT_EQ(db.ids(), (std::vector<KeyframeId>{992, 993, 994, 995, 996, 997, 998, 999}));
  // Compacted: candidates still come from the eight, best η first.
  const auto c = db.candidates(1000, {{60, 1.0}}, 999, 0.0);
  EXPECT_EQ(c.size(), 7u);
}

TEST(KeyframeDatabase, CandidatesAreAboveTheThresholdBestFirstWithoutThePreviousKeyframe) {
  const KeyframeDatabase db = example();
  const auto c = db.candidates(21, kQuery, 20, 0.3);
  EXPECT_EQ(ids_of(c), (std::vector<KeyframeId>{12, 10, 14}));
  ASSERT_EQ(c.size(), 3u);
  EXPECT_DOUBLE_EQ(c[0].score, 0.375);
  EXPECT_DOUBLE_EQ(c[0].eta, 0.75);
  EXPECT_DOUBLE_EQ(c[1].eta, 0.5);
  EXPECT_DOUBLE_EQ(c[2].eta, 0.3125);
  for (const auto& x : c) EXPECT_DOUBLE_EQ(x.score, score(kQuery, db.bow(x.id)));

  // The threshold is strict: η = 0.25 is out at 0.25, in just below.
  EXPECT_EQ(ids_of(db.candidates(21, kQuery, 20, 0.25)), (std::vector<KeyframeId>{12, 10, 14}));
  EXPECT_EQ(ids_of(db.candidates(21, kQuery, 20, 0.2499)), (std::vector<KeyframeId>{12, 10, 14, 11}));
  EXPECT_TRUE(db.candidates(21, kQuery, 20, 0.75).empty());
}

TEST(KeyframeDatabase, ThePreviousKeyframeIsNeverACandidateEvenWhenItMatchesBest) {
  const KeyframeDatabase db = example();
  // With keyframe 12 as "previous", 20 becomes an ordinary earlier keyframe and 12 drops out.
  // η now: 20 0.5/0.375, 10 0.25/0.375, 14 0.15625/0.375, 11 0.125/0.375 = 1/3.
  const auto c = db.candidates(21, kQuery, 12, 0.3);
  EXPECT_EQ(ids_of(c), (std::vector<KeyframeId>{20, 10, 14, 11}));
  ASSERT_FALSE(c.empty());
  EXPECT_DOUBLE_EQ(c[0].eta, 0.5 / 0.375);  // > 1: a keyframe more like the query than the previous one
}

TEST(KeyframeDatabase, OnlyKeyframesAddedBeforeTheQueryAreConsidered) {
  KeyframeDatabase db = example();
  db.add(21, kQuery);
  db.add(22, kQuery);  // later than 21, identical: not a candidate of 21
  const auto c = db.candidates(21, kQuery, 20, 0.3);
  EXPECT_EQ(ids_of(c), (std::vector<KeyframeId>{12, 10, 14}));  // neither 21 itself nor 22
  // Asked for 22, keyframe 21 (identical, η 2) is the best candidate.
  EXPECT_EQ(ids_of(db.candidates(22, kQuery, 20, 0.3)), (std::vector<KeyframeId>{21, 12, 10, 14}));
}

TEST(KeyframeDatabase, NoCandidatesWhenThePreviousScoreIsZeroOrUnknown) {
  const KeyframeDatabase db = example();
  EXPECT_TRUE(db.candidates(21, kQuery, 13, 0.3).empty());       // s(q, v_13) = 0: η undefined
  EXPECT_TRUE(db.candidates(21, kQuery, 99, 0.3).empty());       // no such keyframe
  EXPECT_TRUE(db.candidates(21, BowVector{}, 20, 0.3).empty());  // an image without words
  EXPECT_TRUE(KeyframeDatabase{}.candidates(0, kQuery, -1, 0.3).empty());
}

TEST(KeyframeDatabase, RejectsDuplicateIdsAndMalformedVectors) {
  KeyframeDatabase db;
  db.add(1, {{1, 1.0}});
  EXPECT_THROW(db.add(1, {{2, 1.0}}), std::invalid_argument);
  EXPECT_THROW(db.add(2, {{3, 0.5}, {2, 0.5}}), std::invalid_argument);  // unsorted
  EXPECT_THROW(db.add(3, {{2, 0.5}, {2, 0.5}}), std::invalid_argument);  // repeated word
  EXPECT_THROW(db.add(4, {{2, 0.0}}), std::invalid_argument);
  EXPECT_EQ(db.size(), 1u);
  EXPECT_TRUE(db.contains(1));
  EXPECT_FALSE(db.contains(2));
  EXPECT_THROW((void)db.bow(2), std::out_of_range);
}

// The inverted index gives exactly what scoring every earlier keyframe by hand gives.
TEST(KeyframeDatabase, InvertedIndexAgreesWithBruteForce) {
  std::mt19937 rng(4);
  const auto random_bow = [&] {
    std::vector<WordId> words(60);
    std::iota(words.begin(), words.end(), WordId{0});
    std::shuffle(words.begin(), words.end(), rng);
    words.resize(1 + rng() % 20);
    std::sort(words.begin(), words.end());
    BowVector v;
    double total = 0;
    for (const WordId w : words) v.push_back({w, 1.0 + rng() % 7}), total += v.back().weight;
    for (auto& e : v) e.weight /= total;
    return v;
  };
  KeyframeDatabase db;
  std::vector<BowVector> bows;
  for (KeyframeId id = 0; id < 200; ++id) db.add(id, bows.emplace_back(random_bow()));
  for (KeyframeId query = 2; query < 200; query += 7) {
    const BowVector& q = bows[static_cast<std::size_t>(query)];
    std::vector<KeyframeId> expected;
    const double reference = score(q, bows[static_cast<std::size_t>(query - 1)]);
    std::vector<std::pair<double, KeyframeId>> ranked;
    for (KeyframeId j = 0; j + 1 < query; ++j)
      if (reference > 0 && score(q, bows[static_cast<std::size_t>(j)]) / reference > 0.3)
        ranked.push_back({score(q, bows[static_cast<std::size_t>(j)]) / reference, j});
    std::stable_sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    for (const auto& r : ranked) expected.push_back(r.second);
    EXPECT_EQ(ids_of(db.candidates(query, q, query - 1, 0.3)), expected) << "query " << query;
  }
}

}  // namespace
}  // namespace cvo::loop_closure
