// The committed default vocabulary on real frames (tests/data/fr1_rpy_50, 30 Hz): neighbouring
// frames score higher than frames far apart in the clip and than unrelated (rendered) images, and
// the keyframe database proposes the right loop on a revisited view.
#include <cstddef>
#include <optional>
#include <vector>

#include <gtest/gtest.h>

#include "libcvo/core/parameters.hpp"
#include "libcvo/loop_closure/keyframe_database.hpp"
#include "libcvo/loop_closure/vocabulary.hpp"
#include "loop_closure/test_images.hpp"

namespace cvo::loop_closure {
namespace {

class DefaultVocabularyOnRealFrames : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    vocabulary_ = Vocabulary::load(CVO_DEFAULT_VOCABULARY);
    for (std::size_t i = 0; i < 50; i += 2)
      frames_.push_back(vocabulary_->transform(testing::orb(testing::sample_frame(i))));
  }
  static void TearDownTestSuite() {
    frames_.clear();
    vocabulary_.reset();
  }
  // Every second frame of the clip: neighbours are 1/15 s apart.
  static const std::vector<BowVector>& frames() { return frames_; }
  static const Vocabulary& vocabulary() { return *vocabulary_; }

 private:
  // Loaded and transformed once for the suite (ORB on 25 frames is most of its time).
  static inline std::optional<Vocabulary> vocabulary_;
  static inline std::vector<BowVector> frames_;
};

TEST_F(DefaultVocabularyOnRealFrames, NeighboursScoreAboveFarFramesAndUnrelatedImages) {
  const auto& f = frames();
  const std::size_t n = f.size(), far = n / 2;  // ~0.8 s apart: the camera has rolled or pitched away
  std::vector<BowVector> unrelated;
  for (const double t : {0.0, 3.0, 6.0, 9.0})
    unrelated.push_back(vocabulary().transform(testing::orb(testing::room_frame(t))));
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const double neighbour = score(f[i], f[i + 1]);
    // Seen here: neighbours 0.22..0.44, far 0.06..0.09, rendered 0.07..0.14 (k 10, L 4).
    EXPECT_GT(neighbour, 2.0 * score(f[i], f[(i + far) % n])) << "frame " << 2 * i;
    for (std::size_t u = 0; u < unrelated.size(); ++u)
      EXPECT_GT(neighbour, 1.5 * score(f[i], unrelated[u])) << "frame " << 2 * i << ", rendered image " << u;
  }
}

TEST_F(DefaultVocabularyOnRealFrames, KeyframeDatabaseFindsARevisitedViewAndSkipsThePreviousKeyframe) {
  // Keyframes: frames 0, 10, ..., 40; then frame 2 again as a new keyframe 5 after keyframe 4
  // (frame 40). Its loop must be keyframe 0 (frame 0), best first; keyframe 4 never appears.
  const auto& f = frames();
  KeyframeDatabase db;
  for (KeyframeId k = 0; k < 5; ++k) db.add(k, f[static_cast<std::size_t>(5 * k)]);
  const BowVector revisit = f[1];
  db.add(5, revisit);
  const auto c = db.candidates(5, revisit, 4, core::LoopClosureParameters{}.similarity_threshold);
  ASSERT_FALSE(c.empty());
  EXPECT_EQ(c.front().id, 0);
  for (const auto& x : c) EXPECT_NE(x.id, 4);
}

}  // namespace
}  // namespace cvo::loop_closure
