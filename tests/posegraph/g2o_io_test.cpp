#include "libcvo/posegraph/g2o_io.hpp"

#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "libcvo/core/information.hpp"
#include "libcvo/io/input_error.hpp"
#include "libcvo/posegraph/cost.hpp"
#include "libcvo/posegraph/optimizer.hpp"
#include "tests/posegraph/indefinite_graph.hpp"
#include "tests/support/temp_dir.hpp"

namespace cvo::posegraph {
namespace {

using core::Matrix6d;
using core::SE3;
using core::Vector6d;
using Eigen::Vector3d;

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

// Entry k of the 21 is k, plus 1000 on the diagonal (so the matrix is positive definite and read
// as it is, not repaired).
TEST(G2oIo, ReadsTheInformationUpperTriangleRowMajor) {
  std::stringstream text(
      "# comment\n"
      "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\n"
      "VERTEX_SE3:QUAT 1 1 0 0 0 0 0 1\n"
      "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1  1001 2 3 4 5 6  1007 8 9 10 11  1012 13 14 15  1016 17 18  1019 20  1021\n"
      "FIX 1\n");
  std::ostringstream warnings;
  const PoseGraph g = parse_g2o(text, "mem.g2o", warnings);
  EXPECT_EQ(warnings.str(), "");
  const Matrix6d& I = g.edges().at(0).information;
  EXPECT_EQ(I(0, 5), 6);
  EXPECT_EQ(I(5, 0), 6);
  EXPECT_EQ(I(1, 1), 1007);
  EXPECT_EQ(I(2, 4), 14);
  EXPECT_EQ(I(4, 2), 14);
  EXPECT_EQ(I(5, 5), 1021);
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

// indefinite_graph.hpp: two indefinite information matrices among good edges.
TEST(G2oIo, IndefiniteInformationIsRepairedWithOneWarningNamingFileAndLine) {
  const test::TempDir dir("g2o_io");
  const auto file = dir.write("indefinite.g2o", test_graphs::kIndefiniteGraph);
  std::ostringstream warnings;
  G2oRepairs repairs;
  PoseGraph graph = read_g2o(file, warnings, &repairs);
  EXPECT_EQ(repairs.edges, test_graphs::kIndefiniteEdges);
  EXPECT_EQ(repairs.first_line, test_graphs::kFirstIndefiniteLine);
  const std::string text = warnings.str();
  EXPECT_EQ(text.find('\n'), text.size() - 1) << "one warning line per file:\n" << text;
  EXPECT_NE(text.find(file.string() + ":" + std::to_string(test_graphs::kFirstIndefiniteLine) + ": warning: "),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("not positive semi-definite (eigenvalues -0.2 .. 2.2)"), std::string::npos) << text;
  EXPECT_NE(text.find("2 of 5 edges"), std::string::npos) << text;

  ASSERT_EQ(graph.edges().size(), test_graphs::kEdges);
  for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ(graph.edges()[k].information, Matrix6d::Identity()) << k;  // untouched
  const Matrix6d& repaired = graph.edges()[3].information;
  EXPECT_TRUE(core::check_information(repaired).ok());
  EXPECT_NEAR(repaired(0, 1), 1.1, 1e-8);  // 2.2 along (1, 1)/sqrt2 kept, -0.2 along (1, -1)/sqrt2 gone
  EXPECT_NEAR(repaired(0, 0), 1.1, 1e-8);
  EXPECT_TRUE(core::check_information(graph.edges()[4].information).ok());

  // The minimum is the truth, at a cost of ~0, never below 0 (see indefinite_graph.hpp).
  const auto report = optimize(graph);
  EXPECT_TRUE(report.converged) << report.stop_reason;
  EXPECT_GE(report.final_cost, 0.0);
  EXPECT_LT(report.final_cost, 1e-8);
  EXPECT_GE(cost(graph), 0.0);
  for (const auto& [id, node] : graph.nodes()) {
    EXPECT_LT((node.pose.translation() - Vector3d(static_cast<double>(id), 0, 0)).norm(), 1e-6) << id;
    EXPECT_LT(node.pose.rotation().angularDistance(Eigen::Quaterniond::Identity()), 1e-6) << id;
  }
}

TEST(G2oIo, AGoodFileGivesNoWarning) {
  std::stringstream text(
      "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\nVERTEX_SE3:QUAT 1 1 0 0 0 0 0 1\n"
      "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1 1 0.5 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n");
  std::ostringstream warnings;
  G2oRepairs repairs;
  parse_g2o(text, "good.g2o", warnings, &repairs);
  EXPECT_EQ(warnings.str(), "");
  EXPECT_EQ(repairs.edges, 0u);
  EXPECT_EQ(repairs.first_line, 0u);
}

// A NaN is not repaired towards anything: it is an error naming file and line.
TEST(G2oIo, NanInformationIsAnInputErrorNamingFileAndLine) {
  const test::TempDir dir("g2o_io");
  const auto file = dir.write("nan.g2o",
                              "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\nVERTEX_SE3:QUAT 1 1 0 0 0 0 0 1\n"
                              "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1 1 0 0 0 0 0 1 0 nan 0 0 1 0 0 0 1 0 0 1 0 1\n");
  std::ostringstream warnings;
  try {
    read_g2o(file, warnings);
    FAIL() << "a NaN information entry was accepted";
  } catch (const io::InputError& e) {
    EXPECT_EQ(e.file(), file);
    EXPECT_EQ(e.line(), 3u);
    EXPECT_NE(std::string(e.what()).find(file.string() + ":3: not a finite number: 'nan'"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(warnings.str(), "");
}

TEST(G2oIo, MissingFileIsAnInputError) { EXPECT_THROW(read_g2o("/nonexistent/graph.g2o"), io::InputError); }

}  // namespace
}  // namespace cvo::posegraph
