#include "libcvo/io/covariance_io.hpp"

#include <cmath>
#include <fstream>
#include <iomanip>

#include "libcvo/io/input_error.hpp"
#include "libcvo/io/text_lines.hpp"

namespace cvo::io {

std::vector<StampedCovariance> parse_covariances(std::istream& in, const std::filesystem::path& name) {
  std::vector<StampedCovariance> out;
  for_each_data_line(in, name, [&](std::size_t line_no, const std::vector<std::string>& fields) {
    if (fields.size() != 37)
      throw InputError(
          name, line_no,
          "expected 37 fields 'timestamp' and a 6x6 covariance row-major, got " + std::to_string(fields.size()));
    StampedCovariance c;
    c.timestamp = parse_finite(fields[0], name, line_no);
    for (int k = 0; k < 36; ++k) c.covariance(k / 6, k % 6) = parse_finite(fields[1 + k], name, line_no);
    const double scale = c.covariance.cwiseAbs().maxCoeff();
    if (!((c.covariance - c.covariance.transpose()).cwiseAbs().maxCoeff() <= 1e-6 * scale))
      throw InputError(name, line_no, "the covariance is not symmetric");
    out.push_back(c);
  });
  return out;
}

std::vector<StampedCovariance> read_covariances(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file, "cannot open covariance file");
  return parse_covariances(in, file);
}

void write_covariances(std::ostream& out, const std::vector<StampedCovariance>& covariances) {
  out << "# timestamp, then the 36 entries of the 6x6 covariance row-major, [rho; phi]\n";
  for (const auto& c : covariances) {
    out << std::fixed << std::setprecision(6) << c.timestamp << std::scientific << std::setprecision(9);
    for (int k = 0; k < 36; ++k) out << ' ' << c.covariance(k / 6, k % 6);
    out << '\n';
  }
}

void write_covariances(const std::filesystem::path& file, const std::vector<StampedCovariance>& covariances) {
  std::ofstream out(file);
  if (!out) throw InputError(file, "cannot open for writing");
  write_covariances(out, covariances);
  out.flush();
  if (!out) throw InputError(file, "write failed");
}

}  // namespace cvo::io
