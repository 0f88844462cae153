#pragma once
// Analytic scenes for the synthetic renderer: every surface is a textured planar rectangle, so a
// ray is intersected exactly (no meshes, no approximation) and the distance of any point to the
// scene is known in closed form - the ground truth the back-projection tests check against.
//
// World frame: z up, floor at z = 0. The room is the box [-2, 2] x [-2.5, 2.5] x [0, 2.6] m seen
// from inside; furniture boxes (some rotated about z) stand on the floor and on a table.
//
// white_room is the texture-less room of a real camera: a larger box, [-3.5, 3.5] x [-3.2, 3.2] x
// [0, 2.8] m, so that from the paths' centre (orbit, rpy, fast_rpy) the walls are 3-4 m away (where
// Kinect depth is coarse: 2.6 cm steps at 3 m, kinect_depth.hpp), the same furniture moved out with
// it (positions times 1.5) and two more boxes against the +-x walls, every surface white: a grey albedo in [0.85, 0.95]
// per surface and a tint of at most +-0.01 per channel, no texture. Its light hangs higher (2.6 m, under the ceiling).
// What varies across the image is Lambert shading, smooth over a surface: rendered exactly, every colour is one of a
// few levels; with a camera's colour noise (colour_noise.hpp) every pixel differs by a few noise-driven levels, as on a
// real camera.
//
// Colour of a surface point p with front normal n (viewpoint independent, as brightness-constancy
// methods assume):  rgb = albedo(s, t) * (ambient + (1 - ambient) max(0, n . (light - p)/|light - p|)).
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "libcvo/sim/texture.hpp"

namespace cvo::sim {

enum class SceneKind {
  textured_room,     // room + furniture, rich texture: geometry and appearance
  textureless_room,  // same geometry, one flat colour per surface: geometry only
  textured_wall,     // one large textured plane: appearance only, no structure
  white_room,        // a larger room, white surfaces (see above): structure, no texture
};

std::string_view scene_name(SceneKind kind);
std::optional<SceneKind> parse_scene_kind(std::string_view name);
std::vector<std::string> scene_names();

/// The rectangle {origin + s axis_s + t axis_t : 0 <= s <= length_s, 0 <= t <= length_t}; (s, t) are
/// the texture coordinates in metres. Axes are unit and orthogonal; the front side (the one meant
/// to be seen, used for shading) is axis_s x axis_t. Intersection is two-sided.
struct Quad {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis_s = Eigen::Vector3d::UnitX();
  Eigen::Vector3d axis_t = Eigen::Vector3d::UnitY();
  double length_s = 1.0;
  double length_t = 1.0;

  [[nodiscard]] Eigen::Vector3d normal() const { return axis_s.cross(axis_t); }
};

struct Surface {
  Quad quad;
  Texture texture;
};

/// Surfaces [first, first + count) lie inside `bounds`: a ray that misses the box skips them (the
/// only acceleration structure; five quads per piece of furniture).
struct Object {
  std::size_t first = 0;
  std::size_t count = 0;
  Eigen::AlignedBox3d bounds;
};

struct Scene {
  SceneKind kind = SceneKind::textured_room;
  std::uint64_t seed = 0;
  std::vector<Surface> surfaces;
  std::vector<Object> objects;            // partition surfaces in order
  Eigen::Vector3d light{0.3, -0.4, 2.2};  // point light for Lambert shading, world frame
  double ambient = 0.6;                   // 1 = no shading at all
};

/// Builds a scene; textures (and flat colours) are drawn from the seed, geometry is fixed.
Scene make_scene(SceneKind kind, std::uint64_t seed);

/// The room's interior, shared by all scene kinds but white_room (the textured wall stands where
/// the room's y = +2.5 wall is, so every camera path fits every scene).
Eigen::AlignedBox3d room_bounds();
/// The interior of the room of `kind`: room_bounds(), or white_room's larger box.
Eigen::AlignedBox3d room_bounds(SceneKind kind);

/// Whether the scene's surfaces carry texture (the textured room and wall) or are flat colours.
bool is_textured(SceneKind kind);

/// A ray origin + t direction; direction need not be unit length (t is in units of it).
struct Ray {
  Eigen::Vector3d origin;
  Eigen::Vector3d direction;
};

struct Hit {
  double t = 0;            // ray parameter of the hit
  Eigen::Vector3d point;   // world
  Eigen::Vector3d normal;  // unit front normal of the surface hit (not flipped towards the ray)
  int surface = -1;        // index into Scene::surfaces
  Eigen::Vector2d st;      // texture coordinates, metres
};

/// Nearest hit with t > 0, or nothing when the ray leaves the scene.
std::optional<Hit> intersect(const Scene& scene, const Ray& ray);

/// Euclidean distance from p to the rectangle.
double distance_to_quad(const Quad& quad, const Eigen::Vector3d& p);
/// Euclidean distance from p to the nearest surface of the scene.
double distance_to_surface(const Scene& scene, const Eigen::Vector3d& p);

/// Shaded colour (RGB in [0, 1]) of a hit, see the header comment.
Eigen::Vector3d surface_colour(const Scene& scene, const Hit& hit);

}  // namespace cvo::sim
