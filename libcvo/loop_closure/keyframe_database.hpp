#pragma once
// The bag-of-words vectors of the keyframes so far, with an inverted index (word -> keyframes
// that contain it), for loop-closure candidates as in paper section 5:
//
//   for the current keyframe i with BoW vector v_i and the previous keyframe i-1,
//     η(v_i, v_j) = s(v_i, v_j) / s(v_i, v_{i-1})        (s: the L1 score, vocabulary.hpp)
//   for every earlier keyframe j other than i-1, and j is a candidate when η > η_thres
//   (core::LoopClosureParameters::similarity_threshold, 0.3).
//
// The previous keyframe is left out because keyframe odometry already links it to i; it only
// normalises, since the score range depends on the image and the vocabulary. Edge cases:
//   * s(v_i, v_{i-1}) == 0 (no common words, e.g. an empty vector), or i-1 not in the database:
//     η is undefined and there are no candidates;
//   * η may exceed 1 (a keyframe j more like i than i-1 is: a strong loop);
//   * a keyframe that shares no word with i has s = 0, hence η = 0: never a candidate for
//     min_eta >= 0.
// Only keyframes sharing a word with v_i are visited (the inverted index); the scores are the
// same numbers score() gives.
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "libcvo/loop_closure/vocabulary.hpp"

namespace cvo::loop_closure {

using KeyframeId = std::int64_t;

struct LoopCandidate {
  KeyframeId id = 0;
  double score = 0;  // s(v_i, v_j)
  double eta = 0;    // s(v_i, v_j) / s(v_i, v_{i-1})
};

class KeyframeDatabase {
 public:
  /// Appends a keyframe. Throws std::invalid_argument when the id is already there or bow is not
  /// a BowVector (entries sorted by word, each once, positive finite weights).
  void add(KeyframeId id, BowVector bow);

  /// Removes a keyframe (a localizing session's window moving on, slam/mapper.hpp): it is never a
  /// candidate again. Removed entries are compacted away once they outnumber the kept ones, so a
  /// database that keeps a bounded number of keyframes holds bounded memory. Throws
  /// std::out_of_range when the id is not there.
  void remove(KeyframeId id);

  [[nodiscard]] std::size_t size() const { return position_.size(); }
  [[nodiscard]] bool contains(KeyframeId id) const { return position_.contains(id); }
  /// Keyframe id's vector; std::out_of_range when it is not there.
  [[nodiscard]] const BowVector& bow(KeyframeId id) const { return bows_[position_.at(id)]; }
  /// The keyframes held, in insertion order.
  [[nodiscard]] std::vector<KeyframeId> ids() const;

  /// Loop-closure candidates of keyframe query_id with vector `bow`: the keyframes added before
  /// query_id (all of them when query_id is not in the database), except previous_id and query_id,
  /// whose η = s(bow, v_j) / s(bow, v_previous) > min_eta; best η first, ties in insertion order.
  /// Empty when previous_id is not in the database or s(bow, v_previous) == 0.
  [[nodiscard]] std::vector<LoopCandidate> candidates(KeyframeId query_id, const BowVector& bow, KeyframeId previous_id,
                                                      double min_eta) const;
  /// The same with the normaliser's vector given and none left out (the predecessor was merged
  /// into the keyframe that covers it, which normalises in its place: slam/mapper.hpp).
  [[nodiscard]] std::vector<LoopCandidate> candidates(KeyframeId query_id, const BowVector& bow,
                                                      const BowVector& previous_bow, double min_eta) const {
    return candidates(query_id, bow, previous_bow, min_eta, kNone);
  }

 private:
  struct Posting {
    std::uint32_t keyframe;  // position in ids_
    double weight;
  };
  void compact();
  static constexpr std::uint32_t kNone = 0xffffffffU;
  [[nodiscard]] std::vector<LoopCandidate> candidates(KeyframeId query_id, const BowVector& bow,
                                                      const BowVector& previous_bow, double min_eta,
                                                      std::uint32_t excluded) const;

  std::vector<KeyframeId> ids_;  // by position; removed ones stay until compact() (bows_ empty)
  std::vector<BowVector> bows_;
  std::unordered_map<KeyframeId, std::uint32_t> position_;
  std::vector<std::vector<Posting>> inverted_;  // by word; grows to the largest word seen
};

}  // namespace cvo::loop_closure
