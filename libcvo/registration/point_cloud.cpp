#include "libcvo/registration/point_cloud.hpp"

namespace cvo::registration {

PointCloud::PointCloud(std::size_t capacity) : x_(capacity), y_(capacity), z_(capacity) {
  for (auto& channel : f_) channel.resize(capacity);
}

bool PointCloud::push_back(const Eigen::Vector3f& p, const Feature& f) {
  if (size_ == capacity()) {
    ++overflowed_;
    return false;
  }
  x_[size_] = p.x();
  y_[size_] = p.y();
  z_[size_] = p.z();
  for (std::size_t c = 0; c < kFeatureDim; ++c) f_[c][size_] = f[c];
  ++size_;
  return true;
}

Feature PointCloud::feature(std::size_t i) const {
  Feature f{};
  for (std::size_t c = 0; c < kFeatureDim; ++c) f[c] = f_[c][i];
  return f;
}

}  // namespace cvo::registration
