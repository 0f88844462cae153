#include "libcvo/core/se3.hpp"

#include <cmath>

namespace cvo::core {
namespace {

// Below this angle the closed forms lose precision to cancellation; two Taylor terms are exact
// to double precision there (the next term is ~th^4 / 720).
constexpr double kSmallAngle = 1e-4;

// Left Jacobian of SO(3) and its inverse, the "V" matrices of the SE(3) exponential.
// 1 - cos th is written 2 sin^2(th/2) to avoid cancellation.
Eigen::Matrix3d left_jacobian(const Eigen::Vector3d& phi) {
  const double th = phi.norm();
  const double th2 = th * th;
  const Eigen::Matrix3d W = hat(phi);
  if (th < kSmallAngle) return Eigen::Matrix3d::Identity() + (0.5 - th2 / 24.0) * W + (1.0 / 6.0 - th2 / 120.0) * W * W;
  const double s = std::sin(0.5 * th);
  return Eigen::Matrix3d::Identity() + 2.0 * s * s / th2 * W + (th - std::sin(th)) / (th2 * th) * W * W;
}

}  // namespace

Eigen::Matrix3d hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d m;
  m << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return m;
}

Eigen::Matrix3d so3_left_jacobian_inverse(const Eigen::Vector3d& phi) {
  const double th = phi.norm();
  const double th2 = th * th;
  const Eigen::Matrix3d W = hat(phi);
  // c = (1 - (th/2) cot(th/2)) / th^2
  const double c = th < kSmallAngle ? 1.0 / 12.0 + th2 / 720.0 : (1.0 - 0.5 * th / std::tan(0.5 * th)) / th2;
  return Eigen::Matrix3d::Identity() - 0.5 * W + c * W * W;
}

Eigen::Quaterniond so3_exp(const Eigen::Vector3d& phi) {
  const double th = phi.norm();
  if (th < 1e-8) {
    // q = [cos(th/2), sin(th/2)/th * phi] to second order, exact to double here.
    const Eigen::Quaterniond q(1.0 - th * th / 8.0, 0.5 * phi.x(), 0.5 * phi.y(), 0.5 * phi.z());
    return q.normalized();
  }
  return Eigen::Quaterniond(Eigen::AngleAxisd(th, phi / th));
}

Eigen::Vector3d so3_log(const Eigen::Quaterniond& q_in) {
  // q and -q are the same rotation; pick w >= 0 so the angle lands in [0, pi].
  Eigen::Quaterniond q = q_in.normalized();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const double n = q.vec().norm();
  if (n < 1e-8) return 2.0 * q.vec() / q.w();  // atan(n/w)/n -> 1/w, exact to double here
  const double th = 2.0 * std::atan2(n, q.w());
  return th / n * q.vec();
}

SE3::SE3(const Eigen::Quaterniond& rotation, const Eigen::Vector3d& translation)
    : q_(rotation.normalized()), t_(translation) {}

SE3::SE3(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation)
    : SE3(Eigen::Quaterniond(rotation), translation) {}

SE3::SE3(const Eigen::Matrix4d& matrix) {
  // Nearest rotation in the Frobenius sense, so a slightly non-orthonormal input is repaired.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(matrix.topLeftCorner<3, 3>(), Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d R = svd.matrixU() * svd.matrixV().transpose();
  if (R.determinant() < 0) {
    Eigen::Matrix3d U = svd.matrixU();
    U.col(2) *= -1.0;
    R = U * svd.matrixV().transpose();
  }
  q_ = Eigen::Quaterniond(R).normalized();
  t_ = matrix.topRightCorner<3, 1>();
}

SE3 SE3::exp(const Vector6d& xi) {
  const Eigen::Vector3d rho = xi.head<3>();
  const Eigen::Vector3d phi = xi.tail<3>();
  return {so3_exp(phi), left_jacobian(phi) * rho};
}

Vector6d SE3::log() const {
  const Eigen::Vector3d phi = so3_log(q_);
  Vector6d xi;
  xi << so3_left_jacobian_inverse(phi) * t_, phi;
  return xi;
}

SE3 SE3::inverse() const {
  const Eigen::Quaterniond qi = q_.conjugate();
  return {qi, -(qi * t_)};
}

Eigen::Matrix4d SE3::matrix() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = q_.toRotationMatrix();
  m.topRightCorner<3, 1>() = t_;
  return m;
}

Matrix6d SE3::adjoint() const {
  const Eigen::Matrix3d R = q_.toRotationMatrix();
  Matrix6d ad = Matrix6d::Zero();
  ad.topLeftCorner<3, 3>() = R;
  ad.topRightCorner<3, 3>() = hat(t_) * R;
  ad.bottomRightCorner<3, 3>() = R;
  return ad;
}

double SE3::angle() const { return so3_log(q_).norm(); }

bool SE3::is_finite() const { return q_.coeffs().allFinite() && t_.allFinite(); }

SE3 SE3::operator*(const SE3& other) const { return {q_ * other.q_, q_ * other.t_ + t_}; }

SE3 interpolate(const SE3& a, const SE3& b, double s) { return a * SE3::exp(s * (a.inverse() * b).log()); }

}  // namespace cvo::core
