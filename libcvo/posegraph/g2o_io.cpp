#include "libcvo/posegraph/g2o_io.hpp"

#include <cstdio>
#include <fstream>
#include <ostream>
#include <string>
#include <vector>

#include "libcvo/core/information.hpp"
#include "libcvo/io/input_error.hpp"
#include "libcvo/io/text_lines.hpp"

namespace cvo::posegraph {
namespace {

NodeId parse_id(const std::string& field, const std::filesystem::path& name, std::size_t line) {
  std::size_t used = 0;
  long long id = 0;
  try {
    id = std::stoll(field, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != field.size()) throw io::InputError(name, line, "not an integer id: '" + field + "'");
  return id;
}

// x y z qx qy qz qw starting at fields[first].
core::SE3 parse_pose(const std::vector<std::string>& fields, std::size_t first, const std::filesystem::path& name,
                     std::size_t line) {
  double v[7];
  for (int k = 0; k < 7; ++k) v[k] = io::parse_finite(fields[first + k], name, line);
  const Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
  if (q.norm() < 1e-6) throw io::InputError(name, line, "zero quaternion");
  return {q, Eigen::Vector3d(v[0], v[1], v[2])};
}

void expect_fields(const std::vector<std::string>& fields, std::size_t n, const std::filesystem::path& name,
                   std::size_t line) {
  if (fields.size() != n)
    throw io::InputError(
        name, line,
        fields[0] + " needs " + std::to_string(n - 1) + " values, not " + std::to_string(fields.size() - 1));
}

// EDGE_SE3:QUAT i j x y z qx qy qz qw I11 .. I66 (fields already counted).
Edge parse_edge(const std::vector<std::string>& fields, const std::filesystem::path& name, std::size_t line) {
  Edge e;
  e.from = parse_id(fields[1], name, line);
  e.to = parse_id(fields[2], name, line);
  e.measurement = parse_pose(fields, 3, name, line);
  std::size_t k = 10;
  for (int r = 0; r < 6; ++r)
    for (int c = r; c < 6; ++c) e.information(r, c) = e.information(c, r) = io::parse_finite(fields[k++], name, line);
  return e;
}

// The repairs of one file (see the header): made edge by edge, reported once at the end.
struct Repairs {
  G2oRepairs summary;
  core::InformationCheck first;  // what was wrong with the first repaired edge

  void repair(Edge& e, std::size_t line) {
    const core::InformationCheck check = core::check_information(e.information);
    if (check.ok()) return;
    if (summary.edges++ == 0) {
      summary.first_line = line;
      first = check;
    }
    e.information = core::nearest_information(e.information);
  }

  void warn(std::ostream& out, const std::filesystem::path& name, std::size_t edges) const {
    if (summary.edges == 0) return;
    out << name.string() << ':' << summary.first_line << ": warning: " << first.why() << "; " << summary.edges << " of "
        << edges << " edges like this one repaired to the nearest positive-definite matrix\n";
  }
};

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

void write_pose(std::ostream& out, const core::SE3& T) {
  const auto& t = T.translation();
  const auto& q = T.rotation();
  out << number(t.x()) << ' ' << number(t.y()) << ' ' << number(t.z()) << ' ' << number(q.x()) << ' ' << number(q.y())
      << ' ' << number(q.z()) << ' ' << number(q.w());
}

}  // namespace

PoseGraph parse_g2o(std::istream& in, const std::filesystem::path& name, std::ostream& warnings, G2oRepairs* repairs) {
  PoseGraph graph;
  struct PendingEdge {
    Edge edge;
    std::size_t line;
  };
  std::vector<PendingEdge> edges;  // added after all vertices, so edges may come first in a file
  std::vector<std::pair<NodeId, std::size_t>> fixes;
  Repairs repaired;
  io::for_each_data_line(in, name, [&](std::size_t line, const std::vector<std::string>& f) {
    const std::string& tag = f[0];
    if (tag == "VERTEX_SE3:QUAT") {
      expect_fields(f, 9, name, line);
      const NodeId id = parse_id(f[1], name, line);
      if (graph.contains(id)) throw io::InputError(name, line, "vertex " + f[1] + " defined twice");
      graph.add_node(id, parse_pose(f, 2, name, line));
    } else if (tag == "EDGE_SE3:QUAT") {
      expect_fields(f, 31, name, line);
      edges.push_back({parse_edge(f, name, line), line});
      repaired.repair(edges.back().edge, line);
    } else if (tag == "FIX") {
      if (f.size() < 2) throw io::InputError(name, line, "FIX needs at least one vertex id");
      for (std::size_t k = 1; k < f.size(); ++k) fixes.emplace_back(parse_id(f[k], name, line), line);
    } else {
      throw io::InputError(name, line,
                           "unsupported g2o tag '" + tag + "' (only VERTEX_SE3:QUAT, EDGE_SE3:QUAT and FIX are read)");
    }
  });
  for (const auto& [e, line] : edges) {
    if (!graph.contains(e.from) || !graph.contains(e.to))
      throw io::InputError(name, line, "edge names an unknown vertex");
    if (e.from == e.to) throw io::InputError(name, line, "edge joins a vertex to itself");
    graph.add_edge(e);
  }
  for (const auto& [id, line] : fixes) {
    if (!graph.contains(id)) throw io::InputError(name, line, "FIX names an unknown vertex");
    graph.set_fixed(id, true);
  }
  repaired.warn(warnings, name, edges.size());
  if (repairs != nullptr) *repairs = repaired.summary;
  return graph;
}

PoseGraph read_g2o(const std::filesystem::path& file, std::ostream& warnings, G2oRepairs* repairs) {
  std::ifstream in(file);
  if (!in) throw io::InputError(file, "cannot open");
  return parse_g2o(in, file, warnings, repairs);
}

void write_g2o(std::ostream& out, const PoseGraph& graph) {
  for (const auto& [id, node] : graph.nodes()) {
    out << "VERTEX_SE3:QUAT " << id << ' ';
    write_pose(out, node.pose);
    out << '\n';
  }
  for (const Edge& e : graph.edges()) {
    out << "EDGE_SE3:QUAT " << e.from << ' ' << e.to << ' ';
    write_pose(out, e.measurement);
    for (int r = 0; r < 6; ++r)
      for (int c = r; c < 6; ++c) out << ' ' << number(e.information(r, c));
    out << '\n';
  }
  for (const auto& [id, node] : graph.nodes())
    if (node.fixed) out << "FIX " << id << '\n';
}

void write_g2o(const std::filesystem::path& file, const PoseGraph& graph) {
  std::ofstream out(file);
  if (!out) throw io::InputError(file, "cannot open for writing");
  write_g2o(out, graph);
  if (!out) throw io::InputError(file, "write error");
}

}  // namespace cvo::posegraph
