#include "libcvo/io/trajectory_io.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "libcvo/io/input_error.hpp"
#include "libcvo/io/text_lines.hpp"

namespace cvo::io {

core::Trajectory parse_tum_trajectory(std::istream& in, const std::filesystem::path& name) {
  core::Trajectory trajectory;
  for_each_data_line(in, name, [&](std::size_t line_no, const std::vector<std::string>& fields) {
    if (fields.size() != 8)
      throw InputError(name, line_no,
                       "expected 8 fields 'timestamp tx ty tz qx qy qz qw', got " + std::to_string(fields.size()));
    std::array<double, 8> v{};
    for (std::size_t k = 0; k < 8; ++k) v[k] = parse_finite(fields[k], name, line_no);
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (q.norm() < 1e-6) throw InputError(name, line_no, "quaternion has zero norm");
    trajectory.push_back({v[0], core::SE3(q, Eigen::Vector3d(v[1], v[2], v[3]))});
  });
  std::stable_sort(trajectory.begin(), trajectory.end(),
                   [](const auto& a, const auto& b) { return a.timestamp < b.timestamp; });
  return trajectory;
}

core::Trajectory read_tum_trajectory(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file, "cannot open trajectory file");
  return parse_tum_trajectory(in, file);
}

void write_tum_trajectory(std::ostream& out, const core::Trajectory& trajectory) {
  out << "# timestamp tx ty tz qx qy qz qw\n";
  for (const auto& [t, pose] : trajectory) {
    const auto& p = pose.translation();
    const auto& q = pose.rotation();
    out << std::fixed << std::setprecision(6) << t << std::setprecision(9) << ' ' << p.x() << ' ' << p.y() << ' '
        << p.z() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << q.w() << '\n';
  }
}

void write_tum_trajectory(const std::filesystem::path& file, const core::Trajectory& trajectory) {
  std::ofstream out(file);
  if (!out) throw InputError(file, "cannot open for writing");
  write_tum_trajectory(out, trajectory);
  out.flush();
  if (!out) throw InputError(file, "write failed");
}

}  // namespace cvo::io
