#pragma once
// A bag-of-words vocabulary tree for binary descriptors, as DBoW2 (Gálvez-López and Tardós,
// "Bags of Binary Words for Fast Place Recognition in Image Sequences", T-RO 2012), which the
// paper's loop closure (section 5) uses through ORB-SLAM2.
//
// Training: hierarchical k-medians. The root holds every training descriptor; a node's
// descriptors are split into (at most) k clusters by k-medians under the Hamming distance,
// seeded by k-means++ (each further seed drawn with probability ∝ D², D the Hamming distance to
// the nearest seed so far); the centre of a cluster is its bitwise majority, which minimises the
// summed Hamming distance to its members (the median per bit; ties give 0). Clusters are split
// again down to depth L. A node becomes a leaf early when its descriptors are all equal; a
// node with at most k distinct descriptors gets one child per distinct descriptor. The leaves are
// the words: at most k^L of them.
//
// Weights: idf(w) = log(N / n_w), N the number of training images and n_w those among them with a
// descriptor that maps to w (a word no training image maps to gets log N, as if seen once).
// transform() maps each descriptor to a word by descending from the root to the nearest child
// (Hamming; ties to the first child), then v_w = tf(w) idf(w) with tf the word's share of the
// image's descriptors, and L1-normalises v. Words in every training image (idf 0) drop out.
//
// Score: DBoW2's L1 score s(a, b) = 1 - |a - b|_1 / 2, in [0, 1] (1: same words in the same
// proportions). For L1-normalised a, b >= 0 it equals Σ_w min(a_w, b_w), which is how it is
// computed; an empty vector (no known words) scores 0 against anything.
//
// Training is deterministic given the seed (each node draws from its own counter-based stream).
//
// File format, version 1 (all integers little-endian, doubles as IEEE-754 binary64 bits):
//   offset  size  field
//   0       6     magic "CVOVOC"
//   6       2     u16 format version (1)
//   8       4     u32 k (branching factor)
//   12      4     u32 L (depth)
//   16      4     u32 node count n
//   20      4     u32 word count (must equal the number of leaves)
//   24      4     u32 training images N
//   28      44 n  nodes in id order (node 0 the root; a node's parent has a smaller id):
//                   u32 parent (0xffffffff for the root), f64 weight (idf, 0..64; 0 for inner nodes),
//                   32 bytes centre (the descriptor's bytes as in an ORB row; zero for the root)
//   28+44n  8     u64 FNV-1a 64 of every byte before it
// Words are numbered in the order of the leaves' node ids.
#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core/mat.hpp>

namespace cvo::loop_closure {

/// A 256-bit binary descriptor (one 32-byte ORB row) as four 64-bit blocks.
using Descriptor = std::array<std::uint64_t, 4>;

/// Number of differing bits, 0..256.
int hamming(const Descriptor& a, const Descriptor& b);

/// The rows of a CV_8UC1 n x 32 matrix (an ORB descriptor matrix; an empty matrix gives none).
/// Throws std::invalid_argument on another type or width.
std::vector<Descriptor> to_descriptors(const cv::Mat& rows);

using WordId = std::uint32_t;

struct BowEntry {
  WordId word = 0;
  double weight = 0;  // > 0
  friend bool operator==(const BowEntry&, const BowEntry&) = default;
};

/// Sparse TF-IDF vector: entries sorted by word, each word once, weights summing to 1; empty
/// when no descriptor fell on a word with a positive weight.
using BowVector = std::vector<BowEntry>;

/// DBoW2's L1 score 1 - |a - b|_1 / 2 of two BoW vectors, in [0, 1]; 0 when either is empty.
double score(const BowVector& a, const BowVector& b);

struct VocabularyParameters {
  int branching = 10;        // k, 2..256
  int levels = 4;            // L, 1..16
  std::uint64_t seed = 0;    // k-means++ seeding
  int max_iterations = 100;  // k-medians iterations per node (stops earlier when stable)
};

class Vocabulary {
 public:
  static constexpr std::uint32_t kNoParent = 0xffffffffu;
  static constexpr std::uint16_t kFormatVersion = 1;

  struct Node {
    std::uint32_t parent = kNoParent;
    double weight = 0;  // idf for a word, 0 for an inner node
    Descriptor centre{};
    friend bool operator==(const Node&, const Node&) = default;
  };

  /// Trains on the descriptors of N images (one CV_8UC1 n x 32 matrix each, as extract_orb gives).
  /// Throws std::invalid_argument on bad parameters, a matrix of another shape, or no descriptor.
  static Vocabulary train(const std::vector<cv::Mat>& image_descriptors, const VocabularyParameters& parameters = {});

  /// The BoW vector of one image's descriptors (CV_8UC1 n x 32; empty gives an empty vector).
  [[nodiscard]] BowVector transform(const cv::Mat& descriptors) const;
  [[nodiscard]] BowVector transform(const std::vector<Descriptor>& descriptors) const;

  /// The word a descriptor falls on.
  [[nodiscard]] WordId word(const Descriptor& d) const;

  [[nodiscard]] int branching() const { return k_; }
  [[nodiscard]] int levels() const { return levels_; }
  [[nodiscard]] std::size_t words() const { return word_nodes_.size(); }
  [[nodiscard]] std::size_t training_images() const { return training_images_; }
  [[nodiscard]] const std::vector<Node>& nodes() const { return nodes_; }
  [[nodiscard]] double idf(WordId w) const { return nodes_.at(word_nodes_.at(w)).weight; }

  /// The file's bytes (format above) and their inverse. from_bytes() throws io::InputError
  /// naming `name` on a wrong magic, an unknown version, a truncated or overlong buffer, a
  /// checksum mismatch or an inconsistent tree; it never allocates more than the buffer implies.
  [[nodiscard]] std::string to_bytes() const;
  static Vocabulary from_bytes(std::string_view bytes, const std::filesystem::path& name);

  /// Writes the file (through a temporary file renamed into place). Throws io::InputError on an
  /// I/O failure.
  void save(const std::filesystem::path& file) const;
  /// Reads and verifies a file as from_bytes(); files over 256 MiB are refused unread.
  static Vocabulary load(const std::filesystem::path& file);

  /// The checksum the file of this vocabulary carries (FNV-1a 64 of the bytes before it).
  [[nodiscard]] std::uint64_t checksum() const;

  friend bool operator==(const Vocabulary& a, const Vocabulary& b) {
    return a.k_ == b.k_ && a.levels_ == b.levels_ && a.training_images_ == b.training_images_ && a.nodes_ == b.nodes_;
  }

 private:
  Vocabulary() = default;
  void index_tree();  // children and words from nodes_' parents

  int k_ = 0, levels_ = 0;
  std::size_t training_images_ = 0;
  std::vector<Node> nodes_;
  // Derived from nodes_: children of node i are child_ids_[child_begin_[i] .. child_begin_[i+1]),
  // in id order; word_nodes_[w] is word w's node, node_words_[i] node i's word (or kNoParent).
  std::vector<std::uint32_t> child_begin_, child_ids_, word_nodes_, node_words_;
};

/// FNV-1a 64 of a byte string (the file checksum).
std::uint64_t fnv1a64(std::string_view bytes);

/// The default vocabulary file: the committed one of the source tree this was built from while
/// it is there (a developer's build, the tests), else the copy `cmake --install` put in
/// share/cvo-slam. Throws io::InputError naming both when neither exists.
std::filesystem::path default_vocabulary_file();

}  // namespace cvo::loop_closure
