#pragma once
// Reading and writing pose graphs in g2o's text format (3-D only):
//   VERTEX_SE3:QUAT id x y z qx qy qz qw
//   EDGE_SE3:QUAT   i j x y z qx qy qz qw  I11 I12 .. I16 I22 .. I26 .. I66   (21 upper-triangular
//                                                                              entries, row-major)
//   FIX id [id ...]                                            -> those nodes are fixed
// Blank lines and '#' comments are skipped. Any other tag is an error (InputError naming file and
// line): silently skipping, say, 2-D vertices would optimise a different graph than the file's.
// Malformed lines, duplicate vertices and edges to unknown vertices are errors too.
//
// Information convention: the 6x6 matrix is used as given, [translation, rotation] order, as the
// information of our residual [rho; phi] (rotation part a rotation vector). g2o itself applies it
// to [t; q.vec] of the error quaternion (half the rotation vector for small errors), so g2o's own
// chi^2 weights rotation 4x less; GTSAM's readG2o and Ceres' pose_graph_3d example (2 q.vec) read
// it as we do, which is what the published costs of these datasets use.
//
// Information that is not positive semi-definite (information.hpp) is REPAIRED, not refused: each
// such matrix is replaced by the nearest positive-definite one (eigenvalues clamped from below at
// 1e-9 of the largest), and the reader writes ONE warning per file to `warnings` (standard error
// by default) naming the file, the first such line and how many edges were repaired:
//   office.g2o:12: warning: information is not positive semi-definite (eigenvalues -0.2 .. 2.2);
//   5021 of 16869 edges like this one repaired to the nearest positive-definite matrix
// Why repair: well-known public datasets have such matrices (off-diagonal terms in the wrong slots
// in 5 021 of 16 869 edges of an office dataset) and would be unusable otherwise, while used as
// given they make the cost unbounded below (a negative "converged" cost). A NaN or infinite entry
// is not repaired: it is an InputError naming file and line, like every other malformed value.
#include <cstddef>
#include <filesystem>
#include <iostream>

#include "libcvo/posegraph/pose_graph.hpp"

namespace cvo::posegraph {

/// What the reader repaired (see above).
struct G2oRepairs {
  std::size_t edges = 0;       // edges whose information matrix was replaced
  std::size_t first_line = 0;  // the line of the first of them; 0 when none
};

/// Throws io::InputError (file and line) on a malformed file; the warning about repaired
/// information matrices goes to `warnings`, and the counts to *repairs when given.
PoseGraph read_g2o(const std::filesystem::path& file, std::ostream& warnings = std::cerr,
                   G2oRepairs* repairs = nullptr);
PoseGraph parse_g2o(std::istream& in, const std::filesystem::path& name, std::ostream& warnings = std::cerr,
                    G2oRepairs* repairs = nullptr);

/// Vertices in id order, then edges, then one FIX line per fixed node; full double precision.
/// The robust flag is not part of the format and is not written.
void write_g2o(std::ostream& out, const PoseGraph& graph);
void write_g2o(const std::filesystem::path& file, const PoseGraph& graph);

}  // namespace cvo::posegraph
