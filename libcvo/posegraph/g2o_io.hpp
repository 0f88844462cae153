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
#include <filesystem>
#include <iosfwd>

#include "libcvo/posegraph/pose_graph.hpp"

namespace cvo::posegraph {

/// Throws io::InputError (file and line) on a malformed file.
PoseGraph read_g2o(const std::filesystem::path& file);
PoseGraph parse_g2o(std::istream& in, const std::filesystem::path& name);

/// Vertices in id order, then edges, then one FIX line per fixed node; full double precision.
/// The robust flag is not part of the format and is not written.
void write_g2o(std::ostream& out, const PoseGraph& graph);
void write_g2o(const std::filesystem::path& file, const PoseGraph& graph);

}  // namespace cvo::posegraph
