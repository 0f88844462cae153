#pragma once
// The local pose graph of the paper's section 4.3: the keyframe m and every frame tracked against
// it, with a keyframe→frame edge T_m^n and a (n-1)→n edge T_{n-1}^n per frame. Information
// matrices are the CVO Hessians of the registrations (registration.hpp). When a new keyframe is
// made the graph is complete and handed to the back end; the next one starts at the new keyframe.
//
// Fixed capacity: nodes and edges live in vectors reserved at construction; the tracker makes a
// new keyframe before a graph would overflow.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "libcvo/core/se3.hpp"

namespace cvo::odometry {

struct LocalGraphNode {
  std::uint64_t frame_index = 0;
  double timestamp = 0;
  core::SE3 pose;  // T_world_camera when tracked (the keyframe's is the graph's anchor)
};

struct LocalGraphEdge {
  std::uint64_t from = 0, to = 0;                           // frame indices
  core::SE3 measurement;                                    // T_from_to: the `to` camera in the `from` camera's frame
  core::Matrix6d information = core::Matrix6d::Identity();  // [translation, rotation] order
};

class LocalGraph {
 public:
  // Filled and emptied once, so that its pages are touched now: in a process that locks its
  // working set (mlockall with MCL_ONFAULT) they are then resident and locked before the tracking
  // thread writes into them, and filling the graph never takes a page fault there.
  explicit LocalGraph(std::size_t capacity = 0) {
    nodes_.reserve(capacity);  // exactly: full() compares against the capacity
    edges_.reserve(2 * capacity);
    nodes_.resize(capacity);
    edges_.resize(2 * capacity);
    clear();
  }

  void clear() {
    nodes_.clear();
    edges_.clear();
  }
  /// False (and nothing added) when the graph is full.
  bool add_node(const LocalGraphNode& node) {
    if (nodes_.size() == nodes_.capacity()) return false;
    nodes_.push_back(node);
    return true;
  }
  bool add_edge(const LocalGraphEdge& edge) {
    if (edges_.size() == edges_.capacity()) return false;
    edges_.push_back(edge);
    return true;
  }

  [[nodiscard]] bool full() const { return nodes_.size() == nodes_.capacity(); }
  [[nodiscard]] bool empty() const { return nodes_.empty(); }
  /// The keyframe: the first node.
  [[nodiscard]] const LocalGraphNode& keyframe() const { return nodes_.front(); }
  [[nodiscard]] const std::vector<LocalGraphNode>& nodes() const { return nodes_; }
  [[nodiscard]] const std::vector<LocalGraphEdge>& edges() const { return edges_; }

 private:
  std::vector<LocalGraphNode> nodes_;
  std::vector<LocalGraphEdge> edges_;
};

}  // namespace cvo::odometry
