#pragma once
// A semi-dense coloured point cloud: positions plus the appearance label of each point, stored as
// structure-of-arrays so the kernel loops read contiguous floats (SIMD-friendly).
//
// Capacity is fixed at construction; push_back() never allocates and reports overflow instead of
// growing, so a cloud can live in a realtime thread.
#include <array>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "libcvo/registration/feature.hpp"

namespace cvo::registration {

class PointCloud {
 public:
  explicit PointCloud(std::size_t capacity = 0);

  [[nodiscard]] std::size_t size() const { return size_; }
  [[nodiscard]] std::size_t capacity() const { return x_.size(); }
  [[nodiscard]] bool empty() const { return size_ == 0; }
  /// Points refused by push_back() since the last clear() because the cloud was full.
  [[nodiscard]] std::size_t overflowed() const { return overflowed_; }

  void clear() {
    size_ = 0;
    overflowed_ = 0;
  }
  /// Appends a point; returns false (and counts the overflow) when the cloud is full.
  bool push_back(const Eigen::Vector3f& position, const Feature& feature);

  [[nodiscard]] Eigen::Vector3f position(std::size_t i) const { return {x_[i], y_[i], z_[i]}; }
  [[nodiscard]] Feature feature(std::size_t i) const;

  // Raw arrays for the kernels: valid entries are [0, size()).
  [[nodiscard]] const float* x() const { return x_.data(); }
  [[nodiscard]] const float* y() const { return y_.data(); }
  [[nodiscard]] const float* z() const { return z_.data(); }
  [[nodiscard]] const float* feature_channel(std::size_t c) const { return f_[c].data(); }

 private:
  std::vector<float> x_, y_, z_;
  std::array<std::vector<float>, kFeatureDim> f_;
  std::size_t size_ = 0;
  std::size_t overflowed_ = 0;
};

}  // namespace cvo::registration
