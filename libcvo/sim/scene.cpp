#include "libcvo/sim/scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "libcvo/core/units.hpp"
#include "libcvo/sim/random.hpp"

namespace cvo::sim {
namespace {

struct KindName {
  SceneKind kind;
  std::string_view name;
};
constexpr std::array kKindNames{
    KindName{SceneKind::textured_room, "textured_room"},
    KindName{SceneKind::textureless_room, "textureless_room"},
    KindName{SceneKind::textured_wall, "textured_wall"},
    KindName{SceneKind::white_room, "white_room"},
};

// Room interior and furniture (centre x, y; base height; size x, y, z; yaw about z in degrees).
// Furniture keeps clear of the middle of the room, where the camera paths run.
const Eigen::Vector3d kRoomMin(-2.0, -2.5, 0.0);
const Eigen::Vector3d kRoomMax(2.0, 2.5, 2.6);
const Eigen::Vector3d kWhiteRoomMin(-3.5, -3.2, 0.0);
const Eigen::Vector3d kWhiteRoomMax(3.5, 3.2, 2.8);
constexpr double kWhiteRoomSpread = 1.5;  // furniture positions scale with the larger room
const Eigen::Vector3d kWhiteRoomLight(0.3, -0.4, 2.6);

struct Furniture {
  double x, y, base, sx, sy, sz, yaw_deg;
};
constexpr std::array kFurniture{
    Furniture{1.2, 1.75, 0.0, 1.1, 0.6, 0.75, 0.0},      // table against the +y wall
    Furniture{1.0, 1.8, 0.75, 0.3, 0.25, 0.3, 20.0},     // box on the table
    Furniture{-1.4, 1.7, 0.0, 0.6, 0.5, 1.7, 25.0},      // tall cabinet
    Furniture{1.35, -1.8, 0.0, 0.5, 0.5, 0.5, 35.0},     // cube
    Furniture{-1.25, -1.6, 0.0, 0.9, 0.5, 0.45, -15.0},  // bench
};

// white_room's own furniture, against the +-x walls, which the room's furniture leaves bare: without
// it a view of that wall holds two planes only, and motion along their common line is unobservable.
constexpr std::array kWhiteRoomFurniture{
    Furniture{3.0, 0.3, 0.0, 0.6, 1.2, 1.0, 10.0},      // sideboard at the +x wall
    Furniture{-2.95, -0.2, 0.0, 0.5, 0.9, 1.4, -20.0},  // shelf at the -x wall
};

// Faces of the box centre + R diag(half) [-1, 1]^3. Face normals point out of the box (furniture)
// or into it (a room seen from inside); the bottom face is left out for furniture, which stands on
// something.
void add_box(std::vector<Quad>& quads, const Eigen::Vector3d& centre, const Eigen::Vector3d& half,
             const Eigen::Matrix3d& rotation, bool inside) {
  const double facing = inside ? -1.0 : 1.0;
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;  // e_b x e_c = e_a
    for (const double side : {-1.0, 1.0}) {
      if (!inside && a == 2 && side < 0) continue;
      Quad q;
      q.axis_s = rotation.col(b);
      q.axis_t = side * facing * rotation.col(c);  // so that axis_s x axis_t = facing * outward normal
      q.length_s = 2 * half[b];
      q.length_t = 2 * half[c];
      q.origin = centre + side * half[a] * rotation.col(a) - half[b] * q.axis_s - half[c] * q.axis_t;
      quads.push_back(q);
    }
  }
}

// Large enough to fill the view from anywhere in the room, even at +-20 degrees off-axis.
Quad wall_geometry() {
  Quad q;
  q.axis_s = Eigen::Vector3d::UnitX();
  q.axis_t = Eigen::Vector3d::UnitZ();  // x cross z = -y: faces into the room
  q.length_s = 12.0;
  q.length_t = 10.0;
  q.origin = Eigen::Vector3d(-6.0, kRoomMax.y(), 1.3 - 5.0);
  return q;
}

// Quads grouped by object, for the bounding-box test of intersect(): the room box and the
// furniture, whose floor positions are multiplied by `spread`.
void add_furniture(std::vector<std::vector<Quad>>& objects, const Furniture& f, double spread) {
  const Eigen::Matrix3d yaw = Eigen::AngleAxisd(core::radians(f.yaw_deg), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  add_box(objects.emplace_back(), {spread * f.x, spread * f.y, f.base + f.sz / 2}, {f.sx / 2, f.sy / 2, f.sz / 2}, yaw,
          false);
}

std::vector<std::vector<Quad>> room_geometry(const Eigen::Vector3d& room_min, const Eigen::Vector3d& room_max,
                                             double spread) {
  std::vector<std::vector<Quad>> objects(1);
  add_box(objects[0], (room_min + room_max) / 2, (room_max - room_min) / 2, Eigen::Matrix3d::Identity(), true);
  for (const auto& f : kFurniture) add_furniture(objects, f, spread);
  return objects;
}

std::vector<std::vector<Quad>> white_room_geometry() {
  auto objects = room_geometry(kWhiteRoomMin, kWhiteRoomMax, kWhiteRoomSpread);
  for (const auto& f : kWhiteRoomFurniture) add_furniture(objects, f, 1.0);
  return objects;
}

std::vector<std::vector<Quad>> geometry(SceneKind kind) {
  switch (kind) {
    case SceneKind::textured_wall: return {{wall_geometry()}};
    case SceneKind::white_room: return white_room_geometry();
    case SceneKind::textured_room:
    case SceneKind::textureless_room: break;
  }
  return room_geometry(kRoomMin, kRoomMax, 1.0);
}

// White paint: grey albedo in [0.85, 0.95], tint within +-0.01 per channel.
Texture white_texture(std::uint64_t seed) {
  Draws draws(seed);
  const double grey = draws.uniform(0.85, 0.95);
  Eigen::Vector3d rgb;
  for (int c = 0; c < 3; ++c) rgb[c] = grey + draws.uniform(-0.01, 0.01);
  return flat_texture(rgb);
}

Texture surface_texture(SceneKind kind, std::uint64_t seed) {
  switch (kind) {
    case SceneKind::textureless_room: return random_flat_texture(seed);
    case SceneKind::white_room: return white_texture(seed);
    case SceneKind::textured_room:
    case SceneKind::textured_wall: break;
  }
  return random_texture(seed);
}

Eigen::AlignedBox3d bounds_of(const std::vector<Quad>& quads) {
  Eigen::AlignedBox3d box;
  for (const Quad& q : quads)
    for (const double a : {0.0, 1.0})
      for (const double b : {0.0, 1.0}) box.extend(q.origin + a * q.length_s * q.axis_s + b * q.length_t * q.axis_t);
  // Padding: rays grazing a face at the edge of the box must still reach the face test.
  const Eigen::Vector3d pad = Eigen::Vector3d::Constant(1e-6);
  return {box.min() - pad, box.max() + pad};
}

// Slab test: does origin + t direction, 0 < t < t_max, pass through the box?
bool ray_meets_box(const Ray& ray, const Eigen::AlignedBox3d& box, double t_max) {
  double t0 = 0.0, t1 = t_max;
  for (int i = 0; i < 3; ++i) {
    const double o = ray.origin[i], d = ray.direction[i];
    if (std::abs(d) < 1e-300) {
      if (o < box.min()[i] || o > box.max()[i]) return false;
      continue;
    }
    double near = (box.min()[i] - o) / d, far = (box.max()[i] - o) / d;
    if (near > far) std::swap(near, far);
    t0 = std::max(t0, near);
    t1 = std::min(t1, far);
    if (t0 > t1) return false;
  }
  return true;
}

}  // namespace

std::string_view scene_name(SceneKind kind) {
  for (const auto& k : kKindNames)
    if (k.kind == kind) return k.name;
  return "unknown";
}

std::optional<SceneKind> parse_scene_kind(std::string_view name) {
  for (const auto& k : kKindNames)
    if (k.name == name) return k.kind;
  return std::nullopt;
}

std::vector<std::string> scene_names() {
  std::vector<std::string> names;
  for (const auto& k : kKindNames) names.emplace_back(k.name);
  return names;
}

Eigen::AlignedBox3d room_bounds() { return {kRoomMin, kRoomMax}; }

Eigen::AlignedBox3d room_bounds(SceneKind kind) {
  return kind == SceneKind::white_room ? Eigen::AlignedBox3d(kWhiteRoomMin, kWhiteRoomMax) : room_bounds();
}

bool is_textured(SceneKind kind) { return kind == SceneKind::textured_room || kind == SceneKind::textured_wall; }

Scene make_scene(SceneKind kind, std::uint64_t seed) {
  Scene scene;
  scene.kind = kind;
  scene.seed = seed;
  if (kind == SceneKind::white_room) scene.light = kWhiteRoomLight;
  for (const auto& quads : geometry(kind)) {
    scene.objects.push_back({scene.surfaces.size(), quads.size(), bounds_of(quads)});
    for (const Quad& q : quads) scene.surfaces.push_back({q, surface_texture(kind, hash(seed, scene.surfaces.size()))});
  }
  return scene;
}

std::optional<Hit> intersect(const Scene& scene, const Ray& ray) {
  // Tolerance on the rectangle bounds, so rays through a shared edge cannot slip between faces.
  constexpr double kEdge = 1e-9;
  double best = std::numeric_limits<double>::infinity();
  int best_index = -1;
  Eigen::Vector2d best_st;
  for (const Object& object : scene.objects) {
    if (!ray_meets_box(ray, object.bounds, best)) continue;
    for (std::size_t i = object.first; i < object.first + object.count; ++i) {
      const Quad& q = scene.surfaces[i].quad;
      const Eigen::Vector3d n = q.normal();
      const double denom = n.dot(ray.direction);
      if (std::abs(denom) < 1e-15) continue;  // parallel to the plane
      const double t = n.dot(q.origin - ray.origin) / denom;
      if (!(t > 0) || t >= best) continue;
      const Eigen::Vector3d rel = ray.origin + t * ray.direction - q.origin;
      const double s = rel.dot(q.axis_s), u = rel.dot(q.axis_t);
      if (s < -kEdge || s > q.length_s + kEdge || u < -kEdge || u > q.length_t + kEdge) continue;
      best = t;
      best_index = static_cast<int>(i);
      best_st = {s, u};
    }
  }
  if (best_index < 0) return std::nullopt;
  Hit hit;
  hit.t = best;
  hit.point = ray.origin + best * ray.direction;
  hit.normal = scene.surfaces[static_cast<std::size_t>(best_index)].quad.normal();
  hit.surface = best_index;
  hit.st = best_st;
  return hit;
}

double distance_to_quad(const Quad& q, const Eigen::Vector3d& p) {
  const Eigen::Vector3d rel = p - q.origin;
  const double s = std::clamp(rel.dot(q.axis_s), 0.0, q.length_s);
  const double t = std::clamp(rel.dot(q.axis_t), 0.0, q.length_t);
  return (rel - s * q.axis_s - t * q.axis_t).norm();
}

double distance_to_surface(const Scene& scene, const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& surface : scene.surfaces) best = std::min(best, distance_to_quad(surface.quad, p));
  return best;
}

Eigen::Vector3d surface_colour(const Scene& scene, const Hit& hit) {
  const Surface& surface = scene.surfaces[static_cast<std::size_t>(hit.surface)];
  const Eigen::Vector3d to_light = (scene.light - hit.point).normalized();
  const double lambert = std::max(0.0, hit.normal.dot(to_light));
  return albedo(surface.texture, hit.st.x(), hit.st.y()) * (scene.ambient + (1.0 - scene.ambient) * lambert);
}

}  // namespace cvo::sim
