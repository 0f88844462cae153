// Self-contained check that point_neon matches point_scalar (no Eigen/OpenCV/gtest), meant to be
// cross-compiled for AArch64 and run under qemu-aarch64 by tools/cross/check-neon.
//
// Every fixed-cloud array ends right before a PROT_NONE guard page, so a kernel that reads past the
// end of the last run faults instead of passing. Arrays start at 4-byte (not 16-byte) alignment.
// Thresholds are nudged away from every pair's log a_ij (computed in double), so the keep decision
// is not at the mercy of float rounding and pair counts must match exactly.
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string_view>
#include <vector>

#include "libcvo/registration/kernel.hpp"

using namespace cvo::registration;
using namespace cvo::registration::kernel;

namespace {

// One float array of n elements whose end abuts an inaccessible page.
class GuardedArray {
 public:
  explicit GuardedArray(std::size_t n) : n_(n) {
    const auto page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
    const std::size_t data_pages = (n * sizeof(float) + page - 1) / page;
    bytes_ = (data_pages + 1) * page;
    void* m = mmap(nullptr, bytes_, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (m == MAP_FAILED) std::abort();
    base_ = static_cast<char*>(m);
    char* guard = base_ + data_pages * page;
    if (mprotect(guard, page, PROT_NONE) != 0) std::abort();
    data_ = reinterpret_cast<float*>(guard) - n;
  }
  ~GuardedArray() { munmap(base_, bytes_); }
  GuardedArray(const GuardedArray&) = delete;
  GuardedArray& operator=(const GuardedArray&) = delete;
  float* data() { return data_; }
  float& operator[](std::size_t i) { return data_[i]; }

 private:
  std::size_t n_, bytes_ = 0;
  char* base_ = nullptr;
  float* data_ = nullptr;
};

// kEdge: every other point coincides with the query (log a_ij == log_amplitude exactly, in any
// rounding), the rest are >= ℓ/2 away, and the threshold is log_amplitude: keep means >=, not >.
enum class Mode { kNone, kAll, kMixed, kEdge };
const char* name(Mode m) {
  return m == Mode::kNone ? "none" : m == Mode::kAll ? "all" : m == Mode::kMixed ? "mixed" : "edge";
}

struct Stats {
  int passed = 0, failed = 0;
  double worst = 0;  // worst |neon - scalar| / tolerance scale seen
  long pairs = 0, points = 0;
};

double log_a_double(GuardedArray* cols[8], std::size_t i, const float w[3], const float f[kFeatureDim],
                    const Constants& k) {
  double r2 = 0, c2 = 0;
  for (int d = 0; d < 3; ++d) r2 += std::pow(double(cols[d]->data()[i]) - w[d], 2);
  for (std::size_t c = 0; c < kFeatureDim; ++c) c2 += std::pow(double(cols[3 + c]->data()[i]) - f[c], 2);
  return double(k.log_amplitude) - r2 * k.inv_two_ell_sq - c2 * k.inv_two_ell_color_sq;
}

// One trial: bucket lengths as given, a random subset of buckets (in random order) as the ranges.
void trial(std::mt19937& rng, const std::vector<std::uint32_t>& lengths, Mode mode, bool all_buckets, Stats& st,
           const char* label) {
  std::uniform_real_distribution<float> u(0, 1);
  std::size_t n = 0;
  std::vector<Range> buckets;
  for (auto len : lengths) {
    buckets.push_back({static_cast<std::uint32_t>(n), static_cast<std::uint32_t>(n + len)});
    n += len;
  }
  GuardedArray x(n), y(n), z(n);
  GuardedArray* f[kFeatureDim];
  std::vector<GuardedArray*> owned;
  for (std::size_t c = 0; c < kFeatureDim; ++c) owned.push_back(f[c] = new GuardedArray(n));
  GuardedArray* cols[8] = {&x, &y, &z, f[0], f[1], f[2], f[3], f[4]};

  const float ell = 0.05f + 0.3f * u(rng), ell_c = 0.1f + 0.4f * u(rng);
  const float w[3] = {u(rng) * 2 - 1, u(rng) * 2 - 1, u(rng) * 2 - 1};
  float feature[kFeatureDim];
  for (std::size_t c = 0; c < kFeatureDim; ++c) feature[c] = c < 3 ? u(rng) : u(rng) * 2 - 1;
  // Points within 2..6 ℓ (per axis) of w, colours near the query's: log a_ij in about [-60, 0].
  const float spread = 2 + 4 * u(rng);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = w[0] + (u(rng) * 2 - 1) * spread * ell;
    y[i] = w[1] + (u(rng) * 2 - 1) * spread * ell;
    z[i] = w[2] + (u(rng) * 2 - 1) * spread * ell;
    for (std::size_t c = 0; c < kFeatureDim; ++c) f[c]->data()[i] = feature[c] + (u(rng) * 2 - 1) * ell_c;
    if (mode == Mode::kEdge && i % 2 == 0) {
      x[i] = w[0], y[i] = w[1], z[i] = w[2];
      for (std::size_t c = 0; c < kFeatureDim; ++c) f[c]->data()[i] = feature[c];
    } else if (mode == Mode::kEdge) {
      x[i] = w[0] + (u(rng) < 0.5f ? -1 : 1) * (0.5f + u(rng)) * ell;
    }
  }
  Constants k;
  k.inv_two_ell_sq = 1 / (2 * ell * ell);
  k.inv_two_ell_color_sq = 1 / (2 * ell_c * ell_c);
  k.log_amplitude = std::log(0.1f + u(rng));  // s s_c in [0.1, 1.1)

  std::vector<Range> ranges;
  for (const auto& b : buckets)
    if (all_buckets || u(rng) < 0.7f) ranges.push_back(b);
  std::shuffle(ranges.begin(), ranges.end(), rng);

  std::vector<double> logs;
  for (const auto& r : ranges)
    for (auto i = r.begin; i < r.end; ++i) logs.push_back(log_a_double(cols, i, w, feature, k));
  double thr;
  if (mode == Mode::kNone) {
    thr = k.log_amplitude + 0.5;  // above every log a_ij
  } else if (mode == Mode::kAll) {
    thr = logs.empty() ? -50.0 : *std::min_element(logs.begin(), logs.end()) - 0.5;
  } else if (mode == Mode::kEdge) {
    thr = k.log_amplitude;
  } else {
    thr = logs.empty() ? -1.0 : logs[std::uniform_int_distribution<std::size_t>(0, logs.size() - 1)(rng)];
  }
  for (int tries = 0; tries < 100 && mode != Mode::kEdge; ++tries) {  // move thr off every log a_ij by >= 1e-3
    bool close = false;
    for (double l : logs) close |= std::fabs(l - thr) < 1e-3;
    if (!close) break;
    thr += 2.1e-3;
  }
  k.log_threshold = static_cast<float>(thr);

  // Expected pair count and the magnitudes Σ a, Σ a |x_i - w| (double) for the tolerances.
  std::uint32_t expect_pairs = 0;
  double mag[4] = {0, 0, 0, 0};
  for (const auto& r : ranges)
    for (auto i = r.begin; i < r.end; ++i) {
      const double l = log_a_double(cols, i, w, feature, k);
      if (l < k.log_threshold) continue;
      ++expect_pairs;
      const double a = std::exp(l);
      mag[0] += a;
      for (int d = 0; d < 3; ++d) mag[1 + d] += a * std::fabs(double(cols[d]->data()[i]) - w[d]);
    }

  const FixedCloudView view{
      x.data(), y.data(), z.data(), {f[0]->data(), f[1]->data(), f[2]->data(), f[3]->data(), f[4]->data()}};
  const int count = static_cast<int>(ranges.size());
  const PointSums s = point_scalar(view, ranges.data(), count, w, feature, k);
  const PointSums v = point_neon(view, ranges.data(), count, w, feature, k);

  bool ok = s.pairs == v.pairs && s.pairs == expect_pairs;
  const float sv[4] = {s.a, s.dx, s.dy, s.dz}, vv[4] = {v.a, v.dx, v.dy, v.dz};
  for (int q = 0; q < 4; ++q) {
    // 1e-5 relative, plus 1e-5 of the sum of magnitudes (cancellation in Σ a (x - w)), plus 1e-30.
    const double tol = 1e-5 * std::fabs(sv[q]) + 1e-5 * mag[q] + 1e-30;
    const double err = std::fabs(double(sv[q]) - vv[q]);
    st.worst = std::max(st.worst, err / tol);
    ok &= err <= tol;
  }
  if (mode == Mode::kNone) ok &= v.pairs == 0 && v.a == 0 && v.dx == 0 && v.dy == 0 && v.dz == 0;
  if (mode == Mode::kAll) ok &= v.pairs == logs.size();
  if (mode == Mode::kEdge) ok &= v.pairs == (logs.size() + 1) / 2 || ranges.size() != buckets.size();
  st.pairs += v.pairs;
  st.points += static_cast<long>(logs.size());
  if (ok) {
    ++st.passed;
  } else {
    ++st.failed;
    std::printf(
        "FAIL %s mode=%s ranges=%d points=%zu pairs scalar=%u neon=%u expected=%u\n"
        "     a %.9g vs %.9g  dx %.9g vs %.9g  dy %.9g vs %.9g  dz %.9g vs %.9g\n",
        label, name(mode), count, logs.size(), s.pairs, v.pairs, expect_pairs, s.a, v.a, s.dx, v.dx, s.dy, v.dy, s.dz,
        v.dz);
  }
  for (auto* p : owned) delete p;
}

}  // namespace

int main(int argc, char** argv) {
  const unsigned seed = argc > 1 ? static_cast<unsigned>(std::strtoul(argv[1], nullptr, 10)) : 12345u;
  std::mt19937 rng(seed);
  Stats st;
  // Dispatch: on AArch64 the NEON kernel is the default and is what point_function hands out.
  if (best_isa() == Isa::kNeon && point_function(Isa::kNeon) == &point_neon &&
      point_function(Isa::kAvx2) == &point_scalar && std::string_view(to_string(Isa::kNeon)) == "neon") {
    ++st.passed;
  } else {
    ++st.failed;
    std::printf("FAIL dispatch: best_isa()=%s\n", to_string(best_isa()));
  }
  const Mode modes[] = {Mode::kNone, Mode::kAll, Mode::kMixed, Mode::kEdge};

  for (Mode m : modes) {
    trial(rng, {}, m, true, st, "no ranges");
    trial(rng, {0, 0, 0}, m, true, st, "empty runs");
    // Each run length 0..37 alone: full blocks, every tail length, the run ending at the array's end.
    for (std::uint32_t len = 0; len <= 37; ++len) trial(rng, {len}, m, true, st, "single run");
    // Every length 0..37 in one cloud, all buckets as ranges.
    std::vector<std::uint32_t> every(38);
    for (std::uint32_t len = 0; len <= 37; ++len) every[len] = len;
    trial(rng, every, m, true, st, "all lengths");
  }
  // Random clouds: 0..12 buckets of 0..37 points, a random subset of them as ranges.
  std::uniform_int_distribution<int> bucket_count(0, 12);
  std::uniform_int_distribution<std::uint32_t> bucket_len(0, 37);
  for (int t = 0; t < 800; ++t) {
    std::vector<std::uint32_t> lengths(static_cast<std::size_t>(bucket_count(rng)));
    for (auto& len : lengths) len = bucket_len(rng);
    trial(rng, lengths, modes[t % 4], false, st, "random");
  }

  std::printf(
      "neon_kernel_check (seed %u): %d passed, %d failed; %ld points, %ld pairs kept; "
      "worst error %.3f of tolerance\n",
      seed, st.passed, st.failed, st.points, st.pairs, st.worst);
  return st.failed == 0 ? 0 : 1;
}
