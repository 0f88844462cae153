#include "libcvo/posegraph/incremental_optimizer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/Eigenvalues>

#include "libcvo/posegraph/cholmod_handles.hpp"
#include "libcvo/posegraph/optimizer.hpp"  // send_cholmod_messages_to_stderr
#include "libcvo/posegraph/residual.hpp"

namespace cvo::posegraph {

namespace {

using core::Matrix6d;
using core::SE3;
using core::Vector6d;
using Index = SuiteSparse_long;

// S with SᵀS = M for a symmetric positive semi-definite M: S = Λ^½ Vᵀ (negative round-off → 0).
Matrix6d square_root(const Matrix6d& M) {
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eigen(0.5 * (M + M.transpose()));
  return eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal() * eigen.eigenvectors().transpose();
}

// Upper-triangle triplets of a symmetric matrix, summed into a cholmod_sparse.
class Triplets {
 public:
  Triplets(std::size_t dim, std::size_t capacity, bool pattern, detail::Cholmod& cholmod)
      : cholmod_(cholmod),
        triplet_(cholmod_l_allocate_triplet(dim, dim, capacity, /*stype=upper*/ 1,
                                            pattern ? CHOLMOD_PATTERN : CHOLMOD_REAL, cholmod.common.get())) {
    if (triplet_ == nullptr) throw std::runtime_error("incremental optimizer: CHOLMOD could not allocate");
  }
  ~Triplets() { cholmod_l_free_triplet(&triplet_, cholmod_.common.get()); }
  Triplets(const Triplets&) = delete;
  Triplets& operator=(const Triplets&) = delete;

  void add(Index r, Index c, double value) {
    if (r > c) std::swap(r, c);
    const auto k = static_cast<std::size_t>(triplet_->nnz++);
    static_cast<Index*>(triplet_->i)[k] = r;
    static_cast<Index*>(triplet_->j)[k] = c;
    if (triplet_->xtype == CHOLMOD_REAL) static_cast<double*>(triplet_->x)[k] = value;
  }
  detail::SparsePtr to_sparse() {
    return cholmod_.wrap(cholmod_l_triplet_to_sparse(triplet_, triplet_->nnz, cholmod_.common.get()));
  }

 private:
  detail::Cholmod& cholmod_;
  cholmod_triplet* triplet_;
};

}  // namespace

IncrementalOptimizer::IncrementalOptimizer(IncrementalOptions options)
    : options_(options), kernel_{options.pose_graph.cauchy_delta}, cholmod_(std::make_unique<detail::Cholmod>()) {
  send_cholmod_messages_to_stderr();
}
IncrementalOptimizer::~IncrementalOptimizer() = default;
IncrementalOptimizer::IncrementalOptimizer(IncrementalOptimizer&&) noexcept = default;
IncrementalOptimizer& IncrementalOptimizer::operator=(IncrementalOptimizer&&) noexcept = default;

void IncrementalOptimizer::add_node(NodeId id, const SE3& pose, bool fixed) {
  graph_.add_node(id, pose, fixed);  // its checks
  if (fixed && !nodes_.empty() && !nodes_.front().fixed && nodes_.front().held)
    must_rebuild_ = true;  // the first node was the gauge only: it becomes free
  NodeState node;
  node.id = id;
  node.theta = pose;
  node.fixed = fixed;
  node.held = fixed || nodes_.empty();
  index_.emplace(id, nodes_.size());
  nodes_.push_back(std::move(node));
}

void IncrementalOptimizer::add_edge(const Edge& edge) {
  graph_.add_edge(edge);  // its checks
  EdgeState state;
  state.edge = edge;
  state.i = index_.at(edge.from);
  state.j = index_.at(edge.to);
  nodes_[state.i].edges.push_back(edges_.size());
  nodes_[state.j].edges.push_back(edges_.size());
  edges_.push_back(std::move(state));
}

void IncrementalOptimizer::set_pose(NodeId id, const SE3& pose) {
  NodeState& node = nodes_.at(index_.at(id));
  node.theta = pose;
  node.delta.setZero();
  must_rebuild_ = true;
}

void IncrementalOptimizer::set_fixed(NodeId id, bool fixed) {
  NodeState& node = nodes_.at(index_.at(id));
  if (node.fixed == fixed) return;
  graph_.set_fixed(id, fixed);
  node.fixed = fixed;
  must_rebuild_ = true;
}

const IncrementalOptimizer::NodeState& IncrementalOptimizer::node_state(NodeId id) const {
  return nodes_.at(index_.at(id));
}

SE3 IncrementalOptimizer::pose(NodeId id) const {
  const NodeState& node = node_state(id);
  return node.held ? node.theta : retract(node.theta, node.delta);
}

bool IncrementalOptimizer::fixed(NodeId id) const { return node_state(id).fixed; }

PoseGraph IncrementalOptimizer::graph() const {
  PoseGraph graph = graph_;
  for (const NodeState& node : nodes_) graph.set_pose(node.id, pose(node.id));
  return graph;
}

double IncrementalOptimizer::cost() const {
  double sum = 0;
  for (const EdgeState& e : edges_) {
    const Vector6d r = edge_residual(pose(e.edge.from), pose(e.edge.to), e.edge.measurement);
    sum += kernel_.rho(r.dot(e.edge.information * r), e.edge.robust);
  }
  return 0.5 * sum;
}

std::size_t IncrementalOptimizer::factor_columns() const { return 6 * capacity_; }

// S [J_i J_j] and S e at the nodes' linearisation points, w the Cauchy weight there (IRLS).
void IncrementalOptimizer::linearise(EdgeState& e) {
  const auto lin = linearise_edge(nodes_[e.i].theta, nodes_[e.j].theta, e.edge.measurement);
  const double chi2 = lin.residual.dot(e.edge.information * lin.residual);
  const Matrix6d S = square_root(kernel_.weight(chi2, e.edge.robust) * e.edge.information);
  e.sj << S * lin.jacobian_i, S * lin.jacobian_j;
  e.se = S * lin.residual;
}

void IncrementalOptimizer::add_to_gradient(const EdgeState& e, double sign) {
  const std::array<std::size_t, 2> ends{e.i, e.j};
  for (int side = 0; side < 2; ++side) {
    const NodeState& node = nodes_[ends[side]];
    if (node.held) continue;
    gradient_.segment<6>(6 * node.block) += sign * e.sj.middleCols<6>(6 * side).transpose() * e.se;
  }
}

// The number of columns on the elimination-tree path from `first` to its root (L simplicial: a
// column's parent is its first off-diagonal row), each column counted once per update through
// `marks`.
std::size_t IncrementalOptimizer::mark_path(Index first) {
  const cholmod_factor* L = cholmod_->factor.get();
  const auto* Lp = static_cast<const Index*>(L->p);
  const auto* Li = static_cast<const Index*>(L->i);
  const auto* Lnz = static_cast<const Index*>(L->nz);
  const auto n = static_cast<Index>(L->n);
  std::size_t count = 0;
  for (Index j = first; j >= 0 && j < n;) {
    if (marks_[static_cast<std::size_t>(j)] != 0) break;  // the rest of this path is counted
    marks_[static_cast<std::size_t>(j)] = 1;
    marked_.push_back(j);
    ++count;
    Index parent = n;
    for (Index k = Lp[j]; k < Lp[j] + Lnz[j]; ++k)
      if (Li[k] > j) parent = std::min(parent, Li[k]);
    j = parent;
  }
  return count;
}

// L D Lᵀ ± C Cᵀ with C = (S J)ᵀ on the factor's rows of the edge's free nodes.
std::size_t IncrementalOptimizer::updown(bool update, const EdgeState& e) {
  std::vector<std::pair<Index, int>> rows;  // factor row, column of S J
  const std::array<std::size_t, 2> ends{e.i, e.j};
  for (int side = 0; side < 2; ++side)
    if (const NodeState& node = nodes_[ends[side]]; !node.held)
      for (int c = 0; c < 6; ++c) rows.emplace_back(position_[6 * node.block + c], 6 * side + c);
  if (rows.empty()) return 0;
  std::sort(rows.begin(), rows.end());
  return updown(update, rows, [&](int column, int k) { return e.sj(k, column); });
}

std::size_t IncrementalOptimizer::updown(bool update, const std::vector<std::pair<Index, int>>& rows,
                                         const std::function<double(int, int)>& value) {
  cholmod_common* cc = cholmod_->common.get();
  const auto n = static_cast<std::size_t>(cholmod_->factor->n);
  detail::SparsePtr C =
      cholmod_->wrap(cholmod_l_allocate_sparse(n, 6, 6 * rows.size(), /*sorted=*/1, /*packed=*/1, 0, CHOLMOD_REAL, cc));
  if (!C) throw std::runtime_error("incremental optimizer: CHOLMOD could not allocate");
  auto* Cp = static_cast<Index*>(C->p);
  auto* Ci = static_cast<Index*>(C->i);
  auto* Cx = static_cast<double*>(C->x);
  Index pos = 0;
  for (int k = 0; k < 6; ++k) {
    Cp[k] = pos;
    for (const auto& [row, column] : rows) {
      Ci[pos] = row;
      Cx[pos++] = value(column, k);
    }
  }
  Cp[6] = pos;
  if (!cholmod_l_updown(update ? 1 : 0, C.get(), cholmod_->factor.get(), cc) || cc->status != CHOLMOD_OK)
    must_rebuild_ = true;  // not positive definite (or out of memory): the next step rebuilds
  return mark_path(rows.front().first);
}

// A block's reserved identity leaves H: its node now has an edge there.
std::size_t IncrementalOptimizer::remove_identity(NodeState& node) {
  std::vector<std::pair<Index, int>> rows;
  for (int c = 0; c < 6; ++c) rows.emplace_back(position_[6 * node.block + c], c);
  std::sort(rows.begin(), rows.end());
  node.active = true;
  return updown(false, rows, [](int column, int k) { return column == k ? 1.0 : 0.0; });
}

// nnz(L) of the blocks in use per block, against the same at the last analysis.
bool IncrementalOptimizer::fill_grown() const {
  const double now = static_cast<double>(factor_nonzeros() - 6 * (capacity_ - used_blocks_));
  const double analysed =
      static_cast<double>(analysed_nonzeros_) / static_cast<double>(std::max<std::size_t>(analysed_blocks_, 1));
  return now > options_.fill_growth * analysed * static_cast<double>(used_blocks_);
}

// Blocks for the free nodes that have none; false when the reserved ones run out.
bool IncrementalOptimizer::assign_blocks() {
  for (NodeState& node : nodes_) {
    if (node.held || node.block >= 0) continue;
    if (used_blocks_ == capacity_) return false;
    node.block = static_cast<int>(used_blocks_++);
  }
  return true;
}

std::size_t IncrementalOptimizer::factor_nonzeros() const {
  const cholmod_factor* L = cholmod_->factor.get();
  const auto* Lnz = static_cast<const Index*>(L->nz);
  std::size_t sum = 0;
  for (std::size_t j = 0; j < L->n; ++j) sum += static_cast<std::size_t>(Lnz[j]);
  return sum;
}

// The block ordering: CAMD on the block pattern, old nodes first, then the newest free nodes,
// then the reserved blocks; each block's 6 columns kept together. Sets position_ and returns the
// permutation of H's columns.
std::vector<Index> IncrementalOptimizer::block_ordering() {
  cholmod_common* cc = cholmod_->common.get();
  Triplets pattern(capacity_, capacity_ + edges_.size(), /*pattern=*/true, *cholmod_);
  for (std::size_t b = 0; b < capacity_; ++b) pattern.add(static_cast<Index>(b), static_cast<Index>(b), 0);
  for (const EdgeState& e : edges_)
    if (!nodes_[e.i].held && !nodes_[e.j].held) pattern.add(nodes_[e.i].block, nodes_[e.j].block, 0);
  detail::SparsePtr blocks = pattern.to_sparse();
  std::vector<Index> member(capacity_, 0), order(capacity_);
  for (std::size_t b = used_blocks_; b < capacity_; ++b) member[b] = 2;
  for (std::size_t b = used_blocks_ - std::min(used_blocks_, options_.newest_last); b < used_blocks_; ++b)
    member[b] = 1;
  if (!blocks || !cholmod_l_camd(blocks.get(), nullptr, 0, member.data(), order.data(), cc))
    throw std::runtime_error("incremental optimizer: CHOLMOD ordering failed");
  std::vector<Index> perm(6 * capacity_);
  position_.assign(6 * capacity_, 0);
  for (std::size_t k = 0; k < capacity_; ++k)
    for (int c = 0; c < 6; ++c) {
      perm[6 * k + c] = 6 * order[k] + c;
      position_[static_cast<std::size_t>(6 * order[k] + c)] = static_cast<Index>(6 * k + c);
    }
  return perm;
}

namespace {
// Block (R, C) of H, upper triangle only (the lower comes as the transpose block).
void add_block(Triplets& H, int R, int C, const Matrix6d& M) {
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c)
      if (6 * R + r <= 6 * C + c) H.add(6 * R + r, 6 * C + c, M(r, c));
}
}  // namespace

// H at the linearisation points (every edge), with the identity on blocks whose node has no
// edge; the gradient with it.
void IncrementalOptimizer::assemble() {
  const std::size_t dim = 6 * capacity_;
  Triplets H(dim, 144 * edges_.size() + dim, /*pattern=*/false, *cholmod_);
  gradient_.setZero(static_cast<Eigen::Index>(dim));
  for (NodeState& node : nodes_) node.active = false;
  for (EdgeState& e : edges_) {
    linearise(e);
    e.factored = true;
    add_to_gradient(e, 1.0);
    const Eigen::Matrix<double, 12, 12> block = e.sj.transpose() * e.sj;
    const std::array<NodeState*, 2> ends{&nodes_[e.i], &nodes_[e.j]};
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b)
        if (!ends[a]->held && !ends[b]->held)
          add_block(H, ends[a]->block, ends[b]->block, block.block<6, 6>(6 * a, 6 * b));
    for (NodeState* end : ends) end->active = end->active || !end->held;
  }
  for (const NodeState& node : nodes_)
    if (!node.held && !node.active)
      for (int c = 0; c < 6; ++c) H.add(6 * node.block + c, 6 * node.block + c, 1.0);
  for (std::size_t b = used_blocks_; b < capacity_; ++b)
    for (int c = 0; c < 6; ++c) H.add(static_cast<Index>(6 * b + c), static_cast<Index>(6 * b + c), 1.0);
  cholmod_->matrix = H.to_sparse();
}

namespace {
// The largest damping tried: beyond it the graph is taken to be under-constrained.
constexpr double kMaxDamping = 1e-2;
}  // namespace

// H = L D Lᵀ; when round-off makes an ill-conditioned H (parking-garage) not positive definite,
// H + μ diag(H) with μ = 1e-9, 1e-6, ... as Levenberg-Marquardt damps: the step is then a little
// shorter than Gauss-Newton's, and the fixed point (g = 0) the same.
void IncrementalOptimizer::factorize_damped(cholmod_sparse* H) {
  cholmod_common* cc = cholmod_->common.get();
  const auto* Hp = static_cast<const Index*>(H->p);
  auto* Hx = static_cast<double*>(H->x);
  std::vector<double> diagonal(H->ncol);
  for (std::size_t j = 0; j < H->ncol; ++j) diagonal[j] = Hx[Hp[j + 1] - 1];  // sorted: the diagonal is last
  for (double mu = 0;;) {
    {
      const detail::SerialOpenMp serial;
      cholmod_l_factorize(H, cholmod_->factor.get(), cc);
    }
    // Simplicial LDLᵀ with room to grow per column: what cholmod_updown modifies in place.
    if (cc->status == CHOLMOD_OK && cholmod_l_change_factor(CHOLMOD_REAL, /*to_ll=*/0, /*to_super=*/0, /*to_packed=*/0,
                                                            /*to_monotonic=*/1, cholmod_->factor.get(), cc))
      return;
    mu = mu == 0 ? 1e-9 : 1e3 * mu;
    if (mu > kMaxDamping)
      throw std::runtime_error(
          "incremental optimizer: the system is not positive definite (a node without a constraint?)");
    for (std::size_t j = 0; j < H->ncol; ++j) Hx[Hp[j + 1] - 1] = diagonal[j] + mu * std::max(diagonal[j], 1e-6);
  }
}

// Every node relinearised at its estimate, blocks re-assigned in node order, a new ordering and
// one numeric factorisation: a batch Gauss-Newton step.
void IncrementalOptimizer::rebuild(UpdateReport& report) {
  const bool none_fixed = std::none_of(nodes_.begin(), nodes_.end(), [](const NodeState& n) { return n.fixed; });
  used_blocks_ = 0;
  for (std::size_t k = 0; k < nodes_.size(); ++k) {
    NodeState& node = nodes_[k];
    if (!node.held) node.theta = retract(node.theta, node.delta);
    node.delta.setZero();
    node.held = node.fixed || (k == 0 && none_fixed);
    node.block = node.held ? -1 : static_cast<int>(used_blocks_++);
  }
  capacity_ = std::max(options_.initial_capacity, 2 * used_blocks_);
  std::vector<Index> perm = block_ordering();
  assemble();
  cholmod_sparse* H = cholmod_->matrix.get();
  cholmod_common* cc = cholmod_->common.get();
  cc->nmethods = 1;
  cc->method[0].ordering = CHOLMOD_GIVEN;
  cc->supernodal = CHOLMOD_AUTO;  // supernodal when the factor is large: BLAS; then made simplicial LDLᵀ
  cc->final_ll = 0;               // LDLᵀ, which cholmod_updown modifies in place
  cc->postorder = 0;              // keep the ordering as given: the reserved blocks last
  cholmod_->factor.reset();
  if (H != nullptr) cholmod_->factor = cholmod_->wrap(cholmod_l_analyze_p(H, perm.data(), nullptr, 0, cc));
  cc->postorder = 1;
  factor_flops_ = cc->fl;
  if (!cholmod_->factor) throw std::runtime_error("incremental optimizer: CHOLMOD analysis failed");
  // The factor's rows are H's columns permuted by L->Perm: an update's rows go through its inverse.
  const auto* P = static_cast<const Index*>(cholmod_->factor->Perm);
  for (std::size_t k = 0; k < 6 * capacity_; ++k) position_[static_cast<std::size_t>(P[k])] = static_cast<Index>(k);
  factorize_damped(H);
  cholmod_->matrix.reset();  // the factor is what is kept
  marks_.assign(6 * capacity_, 0);
  marked_.clear();
  analysed_nonzeros_ = factor_nonzeros() - 6 * (capacity_ - used_blocks_);  // less the reserved identity
  analysed_blocks_ = used_blocks_;
  first_new_edge_ = edges_.size();
  must_rebuild_ = false;
  ++rebuilds_;
  report.rebuilt = true;
  report.relinearised_nodes = used_blocks_;
  report.touched_columns = 6 * capacity_;
}

// Δ = -H⁻¹ g: a forward and a back substitution over the whole factor (O(nnz(L))).
void IncrementalOptimizer::solve(UpdateReport& report) {
  cholmod_common* cc = cholmod_->common.get();
  const auto dim = static_cast<std::size_t>(gradient_.size());
  detail::DensePtr b = cholmod_->wrap(cholmod_l_allocate_dense(dim, 1, dim, CHOLMOD_REAL, cc));
  if (!b) throw std::runtime_error("incremental optimizer: CHOLMOD could not allocate");
  Eigen::Map<Eigen::VectorXd>(static_cast<double*>(b->x), gradient_.size()) = -gradient_;
  detail::DensePtr x = cholmod_->wrap(cholmod_l_solve(CHOLMOD_A, cholmod_->factor.get(), b.get(), cc));
  if (!x) throw std::runtime_error("incremental optimizer: CHOLMOD solve failed");
  const Eigen::Map<const Eigen::VectorXd> step(static_cast<const double*>(x->x), gradient_.size());
  report.max_step = 0;
  for (NodeState& node : nodes_) {
    if (node.held || node.block < 0) continue;
    node.delta = node.active ? Vector6d(step.segment<6>(6 * node.block)) : Vector6d::Zero();
    const double largest = node.delta.cwiseAbs().maxCoeff();
    report.max_step = std::isfinite(largest) ? std::max(report.max_step, largest) : largest;
  }
}

std::vector<std::size_t> IncrementalOptimizer::to_relinearise(double threshold) const {
  std::vector<std::size_t> moved;
  for (std::size_t k = 0; k < nodes_.size(); ++k)
    if (!nodes_[k].held && nodes_[k].delta.cwiseAbs().maxCoeff() > threshold) moved.push_back(k);
  return moved;
}

// θ_k ← θ_k (+) Δ_k for the moved nodes; each edge touching one is replaced in H (update with the
// new linearisation, then downdate the old) and in g.
std::vector<std::size_t> IncrementalOptimizer::edges_of(const std::vector<std::size_t>& moved) const {
  std::vector<std::size_t> touched;
  for (const std::size_t k : moved)
    for (const std::size_t e : nodes_[k].edges)
      if (edges_[e].factored) touched.push_back(e);
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  return touched;
}

// What relinearising these edges by rank updates would cost, against one factorisation: each is
// two rank-6 updowns along its elimination-tree path, ~12 · 6 flops per entry of L on the path.
// A path far up a large factor (an old node) costs nearly nnz(L), so a few hundred such edges
// cost more than the rebuild.
bool IncrementalOptimizer::cheaper_to_rebuild(const std::vector<std::size_t>& edges) const {
  const cholmod_factor* L = cholmod_->factor.get();
  const auto* Lp = static_cast<const Index*>(L->p);
  const auto* Li = static_cast<const Index*>(L->i);
  const auto* Lnz = static_cast<const Index*>(L->nz);
  const auto n = static_cast<Index>(L->n);
  double work = 0;
  for (const std::size_t index : edges) {
    const EdgeState& e = edges_[index];
    Index j = n;
    for (const std::size_t k : {e.i, e.j})
      if (!nodes_[k].held) j = std::min(j, position_[6 * static_cast<std::size_t>(nodes_[k].block)]);
    while (j < n) {
      work += 72.0 * static_cast<double>(Lnz[j]);
      if (work > factor_flops_) return true;
      Index parent = n;
      for (Index k = Lp[j]; k < Lp[j] + Lnz[j]; ++k)
        if (Li[k] > j) parent = std::min(parent, Li[k]);
      j = parent;
    }
  }
  return false;
}

void IncrementalOptimizer::relinearise(const std::vector<std::size_t>& moved, UpdateReport& report) {
  for (const std::size_t k : moved) {
    NodeState& node = nodes_[k];
    node.theta = retract(node.theta, node.delta);
    node.delta.setZero();
  }
  const std::vector<std::size_t> touched = edges_of(moved);
  for (const std::size_t index : touched) {
    EdgeState& e = edges_[index];
    const EdgeState old = e;
    add_to_gradient(old, -1.0);
    linearise(e);
    add_to_gradient(e, 1.0);
    report.touched_columns += updown(true, e);
    report.touched_columns += updown(false, old);
  }
  report.relinearised_nodes = moved.size();
}

UpdateReport IncrementalOptimizer::update() {
  const bool new_edges = first_new_edge_ < edges_.size();
  return update(new_edges ? options_.relinearise_threshold : options_.converged_threshold);
}

UpdateReport IncrementalOptimizer::update(double relinearise_threshold) {
  UpdateReport report;
  report.new_edges = edges_.size() - first_new_edge_;
  if (nodes_.empty()) return report;
  const std::vector<std::size_t> moved = to_relinearise(relinearise_threshold);
  const auto free_nodes =
      static_cast<double>(std::count_if(nodes_.begin(), nodes_.end(), [](const NodeState& n) { return !n.held; }));
  if (must_rebuild_)
    report.rebuild_reason = "structure changed";
  else if (!assign_blocks())
    report.rebuild_reason = "capacity";
  else if (static_cast<double>(moved.size()) > options_.rebuild_fraction * free_nodes ||
           (options_.rebuild_when_cheaper && cheaper_to_rebuild(edges_of(moved))))
    report.rebuild_reason = "large correction";
  if (report.rebuild_reason != nullptr) {
    rebuild(report);
  } else {
    relinearise(moved, report);
    for (std::size_t index = first_new_edge_; index < edges_.size(); ++index) {
      EdgeState& e = edges_[index];
      linearise(e);
      add_to_gradient(e, 1.0);
      report.touched_columns += updown(true, e);
      e.factored = true;
    }
    // Only once every new edge is in: a new node may be constrained by its edges together alone
    // (two nodes of a new piece and the loop that joins it).
    for (std::size_t index = first_new_edge_; index < edges_.size(); ++index)
      for (const std::size_t k : {edges_[index].i, edges_[index].j})
        if (!nodes_[k].held && !nodes_[k].active) report.touched_columns += remove_identity(nodes_[k]);
    first_new_edge_ = edges_.size();
    for (const Index j : marked_) marks_[static_cast<std::size_t>(j)] = 0;
    marked_.clear();
    if (must_rebuild_ || fill_grown()) {
      report.rebuild_reason = must_rebuild_ ? "not positive definite" : "fill";
      rebuild(report);
    }
  }
  solve(report);
  if (!std::isfinite(report.max_step)) {                  // a downdate left H singular (CHOLMOD does not check)
    for (NodeState& node : nodes_) node.delta.setZero();  // the rebuild starts from θ
    report.rebuild_reason = "singular";
    rebuild(report);
    solve(report);
  }
  return report;
}

}  // namespace cvo::posegraph
