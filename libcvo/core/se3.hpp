#pragma once
// Rigid-body transforms T = (R, t) in SE(3), stored as a unit quaternion and a translation.
//
// Conventions (the same as Sophus and the TUM benchmark):
//   * T maps points from its source frame to its target frame: p' = R p + t.
//     A camera pose T_world_camera maps camera coordinates to world coordinates.
//   * Composition a * b applies b first, then a.
//   * The tangent vector xi = [rho; phi] in R^6 holds the translational part first, then the
//     rotation vector; exp(xi) = [[exp(phi^), V(phi) rho], [0, 1]] with the left Jacobian
//     V(phi) = I + (1 - cos th)/th^2 phi^ + (th - sin th)/th^3 phi^2, th = |phi|.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace cvo::core {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Skew-symmetric matrix: hat(w) * v == w.cross(v).
Eigen::Matrix3d hat(const Eigen::Vector3d& w);

class SE3 {
 public:
  SE3() = default;  // identity
  /// The quaternion is normalised here, so callers may pass a nearly-unit one (e.g. from a file).
  SE3(const Eigen::Quaterniond& rotation, const Eigen::Vector3d& translation);
  SE3(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation);
  /// From a 4x4 homogeneous matrix; the rotation block is re-orthonormalised.
  explicit SE3(const Eigen::Matrix4d& matrix);

  static SE3 identity() { return {}; }
  /// Exponential map of xi = [rho; phi].
  static SE3 exp(const Vector6d& xi);
  static SE3 from_translation(const Eigen::Vector3d& t) { return {Eigen::Quaterniond::Identity(), t}; }
  static SE3 from_rotation_vector(const Eigen::Vector3d& phi) { return exp((Vector6d() << 0, 0, 0, phi).finished()); }

  /// Logarithm: the xi with exp(xi) == *this, rotation angle in [0, pi].
  [[nodiscard]] Vector6d log() const;
  [[nodiscard]] SE3 inverse() const;
  [[nodiscard]] Eigen::Matrix4d matrix() const;
  /// Adjoint: exp(Ad(T) xi) == T * exp(xi) * T^-1.
  [[nodiscard]] Matrix6d adjoint() const;

  [[nodiscard]] const Eigen::Quaterniond& rotation() const { return q_; }
  [[nodiscard]] Eigen::Matrix3d rotation_matrix() const { return q_.toRotationMatrix(); }
  [[nodiscard]] const Eigen::Vector3d& translation() const { return t_; }
  /// Rotation angle in radians, in [0, pi].
  [[nodiscard]] double angle() const;
  [[nodiscard]] bool is_finite() const;

  SE3 operator*(const SE3& other) const;
  Eigen::Vector3d operator*(const Eigen::Vector3d& point) const { return q_ * point + t_; }

 private:
  Eigen::Quaterniond q_{Eigen::Quaterniond::Identity()};
  Eigen::Vector3d t_{Eigen::Vector3d::Zero()};
};

/// Geodesic interpolation a * exp(s * log(a^-1 b)): s = 0 gives a, s = 1 gives b.
SE3 interpolate(const SE3& a, const SE3& b, double s);

/// Exponential and logarithm of SO(3) on rotation vectors, angle in [0, pi].
Eigen::Quaterniond so3_exp(const Eigen::Vector3d& phi);
Eigen::Vector3d so3_log(const Eigen::Quaterniond& q);

/// Inverse of the left Jacobian of SO(3) (the V⁻¹ of the SE(3) logarithm):
///   I - 1/2 φ^ + (1 - (θ/2) cot(θ/2)) / θ² φ^²,  θ = |φ|.
Eigen::Matrix3d so3_left_jacobian_inverse(const Eigen::Vector3d& phi);

}  // namespace cvo::core
