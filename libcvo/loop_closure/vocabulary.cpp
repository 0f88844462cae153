#include "libcvo/loop_closure/vocabulary.hpp"

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <deque>
#include <fstream>
#include <span>
#include <stdexcept>
#include <system_error>

#include "libcvo/io/input_error.hpp"

namespace cvo::loop_closure {

int hamming(const Descriptor& a, const Descriptor& b) {
  return std::popcount(a[0] ^ b[0]) + std::popcount(a[1] ^ b[1]) + std::popcount(a[2] ^ b[2]) +
         std::popcount(a[3] ^ b[3]);
}

std::vector<Descriptor> to_descriptors(const cv::Mat& rows) {
  if (rows.empty()) return {};
  if (rows.type() != CV_8UC1 || rows.cols != 32)
    throw std::invalid_argument("binary descriptors must be a CV_8UC1 matrix with 32 columns (256 bits)");
  std::vector<Descriptor> out(static_cast<std::size_t>(rows.rows));
  for (int r = 0; r < rows.rows; ++r) std::memcpy(out[static_cast<std::size_t>(r)].data(), rows.ptr(r), 32);
  return out;
}

double score(const BowVector& a, const BowVector& b) {
  // |a - b|_1 = |a|_1 + |b|_1 - 2 Σ min(a_w, b_w), and |a|_1 = |b|_1 = 1.
  double common = 0;
  for (auto i = a.begin(), j = b.begin(); i != a.end() && j != b.end();) {
    if (i->word < j->word) {
      ++i;
    } else if (j->word < i->word) {
      ++j;
    } else {
      common += std::min(i->weight, j->weight);
      ++i, ++j;
    }
  }
  return std::clamp(common, 0.0, 1.0);  // rounding must not leave [0, 1]
}

std::filesystem::path default_vocabulary_file() {
  const std::filesystem::path committed = CVO_COMMITTED_VOCABULARY, installed = CVO_INSTALLED_VOCABULARY;
  if (std::filesystem::is_regular_file(committed)) return committed;
  if (std::filesystem::is_regular_file(installed)) return installed;
  throw io::InputError(installed, "default ORB vocabulary not found (nor " + committed.string() +
                                      "): install cvo-slam, or name a vocabulary file");
}

std::uint64_t fnv1a64(std::string_view bytes) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const char c : bytes) h = (h ^ static_cast<unsigned char>(c)) * 0x100000001b3ULL;
  return h;
}

namespace {

// ---- training -------------------------------------------------------------------------------

// Counter-based random stream (SplitMix64): integer-only, so training gives the same tree on every
// platform and standard library.
class Stream {
 public:
  explicit Stream(std::uint64_t key) : state_(key) {}
  std::uint64_t next() {
    std::uint64_t x = (state_ += 0x9e3779b97f4a7c15ULL);
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
  }
  std::uint64_t below(std::uint64_t n) { return next() % n; }  // bias < n / 2^64: irrelevant here

 private:
  std::uint64_t state_;
};

// Bitwise majority of the members: per bit, 1 when more than half of them have it.
Descriptor majority(const std::vector<Descriptor>& all, std::span<const std::uint32_t> members) {
  std::array<std::uint32_t, 256> ones{};
  for (const std::uint32_t m : members)
    for (int b = 0; b < 4; ++b) {
      const std::uint64_t word = all[m][static_cast<std::size_t>(b)];
      for (int i = 0; i < 64; ++i)
        ones[static_cast<std::size_t>(64 * b + i)] += static_cast<std::uint32_t>((word >> i) & 1U);
    }
  Descriptor centre{};
  for (std::size_t i = 0; i < 256; ++i)
    if (2 * static_cast<std::size_t>(ones[i]) > members.size()) centre[i / 64] |= std::uint64_t{1} << (i % 64);
  return centre;
}

struct Cluster {
  Descriptor centre;
  std::vector<std::uint32_t> members;
};

// k-means++ seeds: the first uniformly, each further one with probability ∝ D². Fewer than k when
// the members have fewer distinct values.
std::vector<Descriptor> seed_centres(const std::vector<Descriptor>& all, const std::vector<std::uint32_t>& members,
                                     int k, Stream& random) {
  std::vector<Descriptor> centres{all[members[random.below(members.size())]]};
  std::vector<std::uint64_t> d2(members.size());
  for (std::size_t i = 0; i < members.size(); ++i) {
    const auto d = static_cast<std::uint64_t>(hamming(all[members[i]], centres[0]));
    d2[i] = d * d;
  }
  while (centres.size() < static_cast<std::size_t>(k)) {
    std::uint64_t total = 0;
    for (const auto v : d2) total += v;
    if (total == 0) break;  // every member equals a centre
    std::uint64_t target = random.below(total);
    std::size_t pick = 0;
    while (target >= d2[pick]) target -= d2[pick++];
    centres.push_back(all[members[pick]]);
    for (std::size_t i = 0; i < members.size(); ++i) {
      const auto d = static_cast<std::uint64_t>(hamming(all[members[i]], centres.back()));
      d2[i] = std::min(d2[i], d * d);
    }
  }
  return centres;
}

std::size_t nearest(const Descriptor& d, const std::vector<Descriptor>& centres) {
  std::size_t best = 0;
  int best_distance = 257;
  for (std::size_t c = 0; c < centres.size(); ++c)
    if (const int h = hamming(d, centres[c]); h < best_distance) best_distance = h, best = c;
  return best;
}

// k-medians of one node's members; non-empty clusters only.
std::vector<Cluster> k_medians(const std::vector<Descriptor>& all, const std::vector<std::uint32_t>& members, int k,
                               int max_iterations, Stream& random) {
  std::vector<Descriptor> centres = seed_centres(all, members, k, random);
  std::vector<std::size_t> label(members.size(), centres.size());  // no cluster yet
  std::vector<std::vector<std::uint32_t>> groups(centres.size());
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    bool changed = false;
    for (auto& g : groups) g.clear();
    for (std::size_t i = 0; i < members.size(); ++i) {
      const std::size_t c = nearest(all[members[i]], centres);
      changed = changed || c != label[i];
      label[i] = c;
      groups[c].push_back(members[i]);
    }
    if (!changed) break;  // same clusters, same centres: converged
    for (std::size_t c = 0; c < centres.size(); ++c)
      if (!groups[c].empty()) centres[c] = majority(all, groups[c]);  // an empty cluster keeps its centre
  }
  std::vector<Cluster> clusters;
  for (std::size_t c = 0; c < centres.size(); ++c)
    if (!groups[c].empty()) clusters.push_back({centres[c], std::move(groups[c])});
  return clusters;
}

// At most k distinct descriptors: one cluster each, holding its copies.
std::vector<Cluster> distinct_clusters(const std::vector<Descriptor>& all, const std::vector<std::uint32_t>& members) {
  std::vector<Cluster> clusters;
  for (const std::uint32_t m : members) {
    auto it = std::find_if(clusters.begin(), clusters.end(), [&](const Cluster& c) { return c.centre == all[m]; });
    if (it == clusters.end()) it = clusters.insert(clusters.end(), Cluster{all[m], {}});
    it->members.push_back(m);
  }
  return clusters;
}

std::size_t count_distinct_up_to(const std::vector<Descriptor>& all, const std::vector<std::uint32_t>& members,
                                 std::size_t limit) {
  std::vector<Descriptor> seen;
  for (const std::uint32_t m : members) {
    if (std::find(seen.begin(), seen.end(), all[m]) == seen.end()) seen.push_back(all[m]);
    if (seen.size() > limit) break;
  }
  return seen.size();
}

// ---- file format ----------------------------------------------------------------------------

constexpr std::string_view kMagic = "CVOVOC";
constexpr std::size_t kHeaderBytes = 28, kNodeBytes = 44, kChecksumBytes = 8;
constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t{256} << 20;
constexpr int kMaxBranching = 256, kMaxLevels = 16;
constexpr double kMaxWeight = 64;

void put_u16(std::string& out, std::uint16_t v) {
  for (int i = 0; i < 2; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}
void put_u32(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}
void put_u64(std::string& out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}
std::uint64_t get_le(std::string_view bytes, std::size_t at, int size) {
  std::uint64_t v = 0;
  for (int i = size - 1; i >= 0; --i)
    v = (v << 8) | static_cast<unsigned char>(bytes[at + static_cast<std::size_t>(i)]);
  return v;
}

std::string hex(std::uint64_t v) {
  char text[17];
  for (int i = 15; i >= 0; --i, v >>= 4) text[i] = "0123456789abcdef"[v & 15];
  text[16] = '\0';
  return text;
}

}  // namespace

// ---- Vocabulary -----------------------------------------------------------------------------

Vocabulary Vocabulary::train(const std::vector<cv::Mat>& image_descriptors, const VocabularyParameters& p) {
  if (p.branching < 2 || p.branching > kMaxBranching || p.levels < 1 || p.levels > kMaxLevels || p.max_iterations < 1)
    throw std::invalid_argument("vocabulary: branching must be 2..256, levels 1..16 and max_iterations >= 1");
  std::vector<Descriptor> all;
  std::vector<std::vector<Descriptor>> per_image;
  for (const cv::Mat& m : image_descriptors) {
    per_image.push_back(to_descriptors(m));
    all.insert(all.end(), per_image.back().begin(), per_image.back().end());
  }
  if (all.empty()) throw std::invalid_argument("vocabulary: no training descriptors");
  if (all.size() >= kNoParent) throw std::invalid_argument("vocabulary: too many training descriptors");

  Vocabulary v;
  v.k_ = p.branching;
  v.levels_ = p.levels;
  v.training_images_ = image_descriptors.size();
  v.nodes_.push_back(Node{});

  // Breadth first, so that the children of a node get consecutive ids and words number level by level.
  struct Pending {
    std::uint32_t node;
    int depth;
    std::vector<std::uint32_t> members;
  };
  std::deque<Pending> queue;
  std::vector<std::uint32_t> everything(all.size());
  for (std::uint32_t i = 0; i < everything.size(); ++i) everything[i] = i;
  queue.push_back({0, 0, std::move(everything)});
  while (!queue.empty()) {
    Pending job = std::move(queue.front());
    queue.pop_front();
    const std::size_t distinct = count_distinct_up_to(all, job.members, static_cast<std::size_t>(p.branching));
    if (distinct < 2) continue;  // nothing to tell apart: a leaf
    Stream random(Stream(p.seed ^ (0xd1b54a32d192ed03ULL * (job.node + std::uint64_t{1}))).next());  // per node
    std::vector<Cluster> clusters = distinct <= static_cast<std::size_t>(p.branching)
                                        ? distinct_clusters(all, job.members)
                                        : k_medians(all, job.members, p.branching, p.max_iterations, random);
    for (Cluster& c : clusters) {
      const auto id = static_cast<std::uint32_t>(v.nodes_.size());
      v.nodes_.push_back(Node{job.node, 0.0, c.centre});
      if (job.depth + 1 < p.levels && c.members.size() > 1) queue.push_back({id, job.depth + 1, std::move(c.members)});
    }
  }
  v.index_tree();

  // idf from how the finished tree maps the training images (as transform() will).
  std::vector<std::uint32_t> images_with(v.words(), 0);
  std::vector<std::size_t> last_image(v.words(), 0);
  for (std::size_t image = 0; image < per_image.size(); ++image)
    for (const Descriptor& d : per_image[image]) {
      const WordId w = v.word(d);
      if (images_with[w] == 0 || last_image[w] != image) ++images_with[w], last_image[w] = image;
    }
  const auto n = static_cast<double>(v.training_images_);
  for (WordId w = 0; w < v.words(); ++w)
    v.nodes_[v.word_nodes_[w]].weight = std::log(n / std::max<double>(images_with[w], 1.0));
  return v;
}

void Vocabulary::index_tree() {
  const std::size_t n = nodes_.size();
  child_begin_.assign(n + 1, 0);
  for (std::size_t i = 1; i < n; ++i) ++child_begin_[nodes_[i].parent + 1];
  for (std::size_t i = 0; i < n; ++i) child_begin_[i + 1] += child_begin_[i];
  child_ids_.assign(n > 0 ? n - 1 : 0, 0);
  std::vector<std::uint32_t> fill(child_begin_.begin(), child_begin_.end() - 1);
  for (std::size_t i = 1; i < n; ++i) child_ids_[fill[nodes_[i].parent]++] = static_cast<std::uint32_t>(i);
  word_nodes_.clear();
  node_words_.assign(n, kNoParent);
  for (std::size_t i = 0; i < n; ++i)
    if (child_begin_[i] == child_begin_[i + 1]) {
      node_words_[i] = static_cast<std::uint32_t>(word_nodes_.size());
      word_nodes_.push_back(static_cast<std::uint32_t>(i));
    }
}

WordId Vocabulary::word(const Descriptor& d) const {
  std::uint32_t node = 0;
  while (child_begin_[node] != child_begin_[node + 1]) {
    std::uint32_t best = child_ids_[child_begin_[node]];
    int best_distance = 257;
    for (std::uint32_t c = child_begin_[node]; c < child_begin_[node + 1]; ++c)
      if (const int h = hamming(d, nodes_[child_ids_[c]].centre); h < best_distance)
        best_distance = h, best = child_ids_[c];
    node = best;
  }
  return node_words_[node];
}

BowVector Vocabulary::transform(const std::vector<Descriptor>& descriptors) const {
  std::vector<WordId> words;
  words.reserve(descriptors.size());
  for (const Descriptor& d : descriptors) words.push_back(word(d));
  std::sort(words.begin(), words.end());
  // Each occurrence adds idf(w): v_w ∝ tf(w) idf(w); the 1 / (number of descriptors) of tf
  // cancels in the L1 normalisation.
  BowVector v;
  double total = 0;
  for (auto i = words.begin(); i != words.end();) {
    const auto j = std::find_if(i, words.end(), [&](WordId w) { return w != *i; });
    const double weight = static_cast<double>(j - i) * idf(*i);
    if (weight > 0) v.push_back({*i, weight}), total += weight;
    i = j;
  }
  for (BowEntry& e : v) e.weight /= total;
  return v;
}

BowVector Vocabulary::transform(const cv::Mat& descriptors) const { return transform(to_descriptors(descriptors)); }

std::string Vocabulary::to_bytes() const {
  std::string out;
  out.reserve(kHeaderBytes + kNodeBytes * nodes_.size() + kChecksumBytes);
  out.append(kMagic);
  put_u16(out, kFormatVersion);
  put_u32(out, static_cast<std::uint32_t>(k_));
  put_u32(out, static_cast<std::uint32_t>(levels_));
  put_u32(out, static_cast<std::uint32_t>(nodes_.size()));
  put_u32(out, static_cast<std::uint32_t>(word_nodes_.size()));
  put_u32(out, static_cast<std::uint32_t>(training_images_));
  for (const Node& node : nodes_) {
    put_u32(out, node.parent);
    put_u64(out, std::bit_cast<std::uint64_t>(node.weight));
    out.append(reinterpret_cast<const char*>(node.centre.data()), 32);  // the ORB row's bytes
  }
  put_u64(out, fnv1a64(out));
  return out;
}

std::uint64_t Vocabulary::checksum() const {
  const std::string bytes = to_bytes();
  return get_le(bytes, bytes.size() - kChecksumBytes, 8);
}

Vocabulary Vocabulary::from_bytes(std::string_view bytes, const std::filesystem::path& name) {
  const auto fail = [&](const std::string& why) { return io::InputError(name, "vocabulary: " + why); };
  if (bytes.size() < kMagic.size() && kMagic.starts_with(bytes))
    throw fail("truncated: " + std::to_string(bytes.size()) + " bytes, shorter than the header");
  if (bytes.size() < kMagic.size() || bytes.substr(0, kMagic.size()) != kMagic)
    throw fail("not a cvo-slam vocabulary file (no \"CVOVOC\" magic)");
  if (bytes.size() < kHeaderBytes + kChecksumBytes)
    throw fail("truncated: " + std::to_string(bytes.size()) + " bytes, shorter than the header");
  if (const auto version = get_le(bytes, 6, 2); version != kFormatVersion)
    throw fail("unknown format version " + std::to_string(version) + " (this build reads version " +
               std::to_string(kFormatVersion) + ")");
  const std::uint64_t k = get_le(bytes, 8, 4), levels = get_le(bytes, 12, 4), n = get_le(bytes, 16, 4),
                      word_count = get_le(bytes, 20, 4), images = get_le(bytes, 24, 4);
  // The node count is checked against the size before anything is allocated from it.
  const std::uint64_t expected = kHeaderBytes + kNodeBytes * n + kChecksumBytes;
  if (bytes.size() < expected)
    throw fail("truncated: the header announces " + std::to_string(n) + " nodes (" + std::to_string(expected) +
               " bytes), the file has " + std::to_string(bytes.size()) + " bytes");
  if (bytes.size() > expected)
    throw fail(std::to_string(bytes.size() - expected) + " unexpected bytes after the checksum");
  const std::uint64_t stored = get_le(bytes, expected - kChecksumBytes, 8);
  if (const std::uint64_t computed = fnv1a64(bytes.substr(0, expected - kChecksumBytes)); stored != computed)
    throw fail("checksum mismatch (stored " + hex(stored) + ", computed " + hex(computed) + "): the file is corrupt");

  // A correct checksum with an impossible tree: a bad writer, not a bad disk; still refused.
  if (k < 2 || k > kMaxBranching || levels < 1 || levels > kMaxLevels)
    throw fail("branching " + std::to_string(k) + " / depth " + std::to_string(levels) + " out of range");
  if (n < 1) throw fail("no nodes");
  Vocabulary v;
  v.k_ = static_cast<int>(k);
  v.levels_ = static_cast<int>(levels);
  v.training_images_ = images;
  v.nodes_.resize(n);
  std::vector<std::uint32_t> depth(n, 0), children(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t at = kHeaderBytes + kNodeBytes * i;
    Node& node = v.nodes_[i];
    node.parent = static_cast<std::uint32_t>(get_le(bytes, at, 4));
    node.weight = std::bit_cast<double>(get_le(bytes, at + 4, 8));
    std::memcpy(node.centre.data(), bytes.data() + at + 12, 32);
    const std::string where = "node " + std::to_string(i) + ": ";
    if (i == 0 ? node.parent != kNoParent : node.parent >= i)
      throw fail(where + "bad parent " + std::to_string(node.parent));
    // idf <= log N < 23 for N < 2^32; the bound keeps sums of weights finite.
    if (!(node.weight >= 0 && node.weight <= kMaxWeight)) throw fail(where + "weight not in [0, 64]");
    if (i > 0) {
      depth[i] = depth[node.parent] + 1;
      if (depth[i] > levels) throw fail(where + "deeper than the depth L = " + std::to_string(levels));
      if (++children[node.parent] > k) throw fail(where + "its parent has more than k children");
    }
  }
  v.index_tree();
  if (v.words() != word_count)
    throw fail("the header announces " + std::to_string(word_count) + " words, the tree has " +
               std::to_string(v.words()) + " leaves");
  return v;
}

void Vocabulary::save(const std::filesystem::path& file) const {
  const std::string bytes = to_bytes();
  // Written beside and renamed into place: a reader never sees half a file.
  std::filesystem::path temporary = file;
  temporary += ".partial";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw io::InputError(file, "cannot write: " + std::generic_category().message(errno));
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) throw io::InputError(file, "write failed");
  }
  std::error_code ec;
  std::filesystem::rename(temporary, file, ec);
  if (ec) {
    std::filesystem::remove(temporary, ec);
    throw io::InputError(file, "cannot write: rename failed");
  }
}

Vocabulary Vocabulary::load(const std::filesystem::path& file) {
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(file, ec);
  if (ec) throw io::InputError(file, "cannot read vocabulary: " + ec.message());
  if (size > kMaxFileBytes) throw io::InputError(file, "vocabulary: larger than 256 MiB, refused");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw io::InputError(file, "cannot read vocabulary: " + std::generic_category().message(errno));
  std::string bytes(static_cast<std::size_t>(size), '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(size));
  bytes.resize(static_cast<std::size_t>(in.gcount()));  // a file that shrank meanwhile reads as truncated
  return from_bytes(bytes, file);
}

}  // namespace cvo::loop_closure
