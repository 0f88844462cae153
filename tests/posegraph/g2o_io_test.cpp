#include "libcvo/posegraph/g2o_io.hpp"

#include <sstream>

#include <gtest/gtest.h>

#include "libcvo/io/input_error.hpp"

namespace cvo::posegraph {
namespace {

using core::Matrix6d;
using core::SE3;
using core::Vector6d;

TEST(G2oIo, WriteThenReadGivesTheSameGraph) {
  PoseGraph graph;
  graph.add_node(3, SE3::exp((Vector6d() << 1.5, -2.25, 1e-9, 0.3, -1.1, 2.9).finished()), true);
  graph.add_node(-7, SE3::exp((Vector6d() << 1e6, 0, -3, 0, 0, 0.1).finished()));
  Edge e;
  e.from = 3;
  e.to = -7;
  e.measurement = SE3::exp((Vector6d() << 0.1, 0.2, 0.3, -0.4, 0.5, 0.6).finished());
  Matrix6d A = Matrix6d::Random();
  e.information = A * A.transpose() + Matrix6d::Identity();
  graph.add_edge(e);

  std::stringstream text;
  write_g2o(text, graph);
  const PoseGraph back = parse_g2o(text, "mem.g2o");
  ASSERT_EQ(back.nodes().size(), 2u);
  ASSERT_EQ(back.edges().size(), 1u);
  for (const auto& [id, node] : graph.nodes()) {
    ASSERT_TRUE(back.contains(id));
    EXPECT_EQ(back.node(id).fixed, node.fixed);
    EXPECT_EQ(back.node(id).pose.translation(), node.pose.translation());
    EXPECT_TRUE(back.node(id).pose.rotation().coeffs().isApprox(node.pose.rotation().coeffs(), 1e-15));
  }
  const Edge& b = back.edges()[0];
  EXPECT_EQ(b.from, 3);
  EXPECT_EQ(b.to, -7);
  EXPECT_EQ(b.measurement.translation(), e.measurement.translation());
  EXPECT_TRUE(b.measurement.rotation().coeffs().isApprox(e.measurement.rotation().coeffs(), 1e-15));
  EXPECT_EQ(b.information, e.information);
}

TEST(G2oIo, ReadsTheInformationUpperTriangleRowMajor) {
  std::stringstream text(
      "# comment\n"
      "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\n"
      "VERTEX_SE3:QUAT 1 1 0 0 0 0 0 1\n"
      "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1  1 2 3 4 5 6  7 8 9 10 11  12 13 14 15  16 17 18  19 20  21\n"
      "FIX 1\n");
  const PoseGraph g = parse_g2o(text, "mem.g2o");
  const Matrix6d& I = g.edges().at(0).information;
  EXPECT_EQ(I(0, 5), 6);
  EXPECT_EQ(I(5, 0), 6);
  EXPECT_EQ(I(1, 1), 7);
  EXPECT_EQ(I(2, 4), 14);
  EXPECT_EQ(I(5, 5), 21);
  EXPECT_TRUE(g.node(1).fixed);
  EXPECT_FALSE(g.node(0).fixed);
}

void expect_error(const std::string& text, std::size_t line, const std::string& fragment) {
  std::stringstream ss(text);
  try {
    parse_g2o(ss, "graph.g2o");
    FAIL() << "no error for: " << text;
  } catch (const io::InputError& e) {
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("graph.g2o"), std::string::npos) << e.what();
  }
}

TEST(G2oIo, MalformedFilesNameTheLine) {
  const std::string v0 = "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\n";
  const std::string v1 = "VERTEX_SE3:QUAT 1 1 0 0 0 0 0 1\n";
  const std::string info = " 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n";
  expect_error(v0 + "VERTEX_SE3:QUAT 1 1 0 0 0 0 1\n", 2, "needs 8 values");
  expect_error(v0 + "VERTEX_SE3:QUAT 1 1 0 zero 0 0 0 1\n", 2, "not a number");
  expect_error(v0 + "VERTEX_SE3:QUAT x1 1 0 0 0 0 0 1\n", 2, "not an integer");
  expect_error(v0 + v0, 2, "defined twice");
  expect_error(v0 + "VERTEX_SE3:QUAT 1 1 0 0 0 0 0 0\n", 2, "zero quaternion");
  expect_error(v0 + v1 + "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1 1 0 0\n", 3, "needs 30 values");
  expect_error(v0 + "\n" + v1 + "EDGE_SE3:QUAT 0 5 1 0 0 0 0 0 1" + info, 4, "unknown vertex");
  expect_error(v0 + v1 + "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1" + info.substr(0, info.size() - 2) + "inf\n", 3,
               "not a finite number");
  expect_error(v0 + "VERTEX_SE2 1 0 0 0\n", 2, "unsupported g2o tag 'VERTEX_SE2'");
  expect_error(v0 + "FIX 9\n", 2, "unknown vertex");
}

TEST(G2oIo, MissingFileIsAnInputError) {
  EXPECT_THROW(read_g2o("/nonexistent/graph.g2o"), io::InputError);
}

}  // namespace
}  // namespace cvo::posegraph
