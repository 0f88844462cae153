#include "libcvo/io/accelerometer.hpp"

#include <algorithm>
#include <fstream>

#include "libcvo/io/input_error.hpp"
#include "libcvo/io/text_lines.hpp"

namespace cvo::io {

std::vector<AccelerometerSample> read_tum_accelerometer(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file, "cannot open accelerometer file");
  std::vector<AccelerometerSample> samples;
  for_each_data_line(in, file, [&](std::size_t line, const std::vector<std::string>& fields) {
    if (fields.size() != 4) throw InputError(file, line, "expected 'timestamp ax ay az'");
    const double t = parse_finite(fields[0], file, line);
    const Eigen::Vector3d a(parse_finite(fields[1], file, line), parse_finite(fields[2], file, line),
                            parse_finite(fields[3], file, line));
    samples.push_back({t, Eigen::Vector3d(-a.x(), -a.y(), a.z())});
  });
  std::stable_sort(samples.begin(), samples.end(), [](const AccelerometerSample& a, const AccelerometerSample& b) {
    return a.timestamp < b.timestamp;
  });
  return samples;
}

std::optional<Eigen::Vector3d> mean_specific_force(const std::vector<AccelerometerSample>& samples, double t,
                                                   double half_window) {
  const auto first = std::lower_bound(samples.begin(), samples.end(), t - half_window,
                                      [](const AccelerometerSample& s, double v) { return s.timestamp < v; });
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  std::size_t n = 0;
  for (auto it = first; it != samples.end() && it->timestamp <= t + half_window; ++it) sum += it->specific_force, ++n;
  if (n == 0) return std::nullopt;
  return sum / static_cast<double>(n);
}

}  // namespace cvo::io
