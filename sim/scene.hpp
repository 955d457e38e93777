#pragma once
// The simulated world: a textured floor (plane z = 0) and boxes standing on it (the landing
// platform; the wall pieces around an opening and the room behind it). One description serves
// both the renderer and the contact model, so what the camera sees is what the vehicle hits.

#include <cstdint>
#include <optional>
#include <vector>

#include "sim/params.hpp"
#include "sim/texture.hpp"

namespace alight::sim {

struct Box {
  enum class Kind { kPlatform, kWall, kRoom };
  Kind kind = Kind::kPlatform;
  Vector3d center_W = Vector3d::Zero();
  Vector3d half_size_m = Vector3d::Constant(0.5);
  int texture = 0;  ///< index into Scene::textures
  /// Its top face mirrors Scene::sky_texture with this share seen straight down
  /// (ReflectionParams); 0: matte.
  double reflectance = 0.0;

  /// Turns the box about world z (its frame O: axes along its sides, origin at its centre).
  void set_yaw(double yaw_rad) {
    yaw_rad_ = yaw_rad;
    R_WO_ = rotation_from_rpy(0, 0, yaw_rad);
  }
  /// Any orientation (a deck that rolls and pitches); yaw_rad() is its heading.
  void set_rotation(const Matrix3d& R_WO) {
    R_WO_ = R_WO;
    yaw_rad_ = yaw_of(R_WO);
  }
  /// A moving box: velocity of its centre and angular velocity in world, so a contact
  /// counts the speed relative to its surface. Zero for everything standing still.
  bool moving = false;
  Vector3d v_W = Vector3d::Zero();
  Vector3d omega_W = Vector3d::Zero();
  /// Velocity of the box's material point at p_W [m/s].
  Vector3d velocity_at(const Vector3d& p_W) const { return v_W + omega_W.cross(p_W - center_W); }
  double yaw_rad() const { return yaw_rad_; }
  const Matrix3d& R_WO() const { return R_WO_; }
  /// Point in the box frame (axes along its sides, origin at its centre).
  Vector3d to_local(const Vector3d& p_W) const { return R_WO().transpose() * (p_W - center_W); }
  bool contains(const Vector3d& p_W) const {
    const Vector3d q = to_local(p_W);
    return (q.cwiseAbs() - half_size_m).maxCoeff() < 0.0;
  }

 private:
  double yaw_rad_ = 0.0;
  Matrix3d R_WO_ = Matrix3d::Identity();
};

/// True geometry of the targets, for SIM_TRUTH and scoring.
struct PlatformTruth {
  Vector3d top_center_W = Vector3d::Zero();  ///< centre of the top face [m]
  Vector3d size_m = Vector3d::Zero();        ///< length (its x), width (its y), height [m]
  double yaw_rad = 0.0;
  // A moving platform (platform.motion) at the time of the truth; zero for a still one.
  bool moving = false;
  double roll_rad = 0.0, pitch_rad = 0.0;  ///< Z-Y-X with yaw_rad
  Vector3d v_W = Vector3d::Zero();         ///< velocity of the top centre [m/s]
  Vector3d omega_W = Vector3d::Zero();     ///< angular velocity, world axes [rad/s]
};
struct OpeningTruth {
  Vector3d center_W = Vector3d::Zero();  ///< centre of the opening in the wall's approach face [m]
  Vector2d size_m = Vector2d::Zero();    ///< width, height [m]
  Vector3d wall_normal_W = -Vector3d::UnitX();  ///< towards the approach side
};

/// Where a ray first meets the scene (Scene::cast_ray).
struct RayHit {
  double distance_m = 0.0;                ///< along the ray from its origin [m]
  Vector3d normal_W = Vector3d::UnitZ();  ///< outward normal of the surface hit
  int box = -1;                           ///< index into Scene::boxes; -1: the floor
};

struct Scene {
  std::vector<Texture> textures;
  int floor_texture = 0;
  std::vector<Box> boxes;
  LightingParams lighting;  ///< after randomisation
  /// LightingParams::casters as boxes: they block the light (with shadows on), nothing else.
  std::vector<Box> shadow_casters;
  /// What a reflective top mirrors (ReflectionParams): a texture on the plane z = sky_z_m.
  int sky_texture = -1;
  double sky_z_m = 0.0;

  /// The lamp's falloff at a point (LightingParams::falloff): multiplies the Lambertian shade.
  double illumination(const Vector3d& p_W) const {
    const double r2 = lighting.lamp_radius_m * lighting.lamp_radius_m;
    return 1.0 + lighting.falloff * (2.0 * r2 / (r2 + (p_W - lighting.lamp_W).squaredNorm()) - 1.0);
  }
  std::optional<PlatformTruth> platform;
  int platform_box = -1;  ///< index of the platform in boxes; -1 without one
  std::optional<OpeningTruth> opening;
  bool has_wall = false;
  /// Wall pieces within this distance of the opening's edge count as its frame [m].
  double frame_margin_m = 0.10;

  /// Where a wall contact at `p_W` counts as the opening's frame.
  bool near_opening_frame(const Vector3d& p_W) const;

  /// The first surface along the ray from `origin_W` in direction `dir_W` (any length, not 0)
  /// within `max_distance_m`: the floor (z = 0, infinite) or a face of a box (slab test, Kay
  /// and Kajiya, SIGGRAPH 1986). An origin inside a box or below the floor is blocked: a hit at
  /// distance 0 whose normal faces the ray. nullopt when nothing is that near, or for a
  /// non-finite or zero ray.
  std::optional<RayHit> cast_ray(const Vector3d& origin_W, const Vector3d& dir_W,
                                 double max_distance_m) const;
};

/// What a seed draws within the scenario's `randomize:` ranges (textures aside).
struct SeededLayout {
  Vector2d platform_center_xy_m = Vector2d::Zero();  ///< centre of the platform's footprint [m]
  double platform_yaw_rad = 0.0;
  LightingParams lighting;  ///< the scenario's lighting, varied
};

/// The seed's draws, cheap (no textures). A randomised platform is redrawn until its footprint
/// keeps randomize.start_clearance_m from the start position (the nominal placement if no draw
/// does), so the vehicle never starts with a rotor over it.
SeededLayout draw_layout(const Scenario& scenario, uint64_t seed);

/// Builds the scene of a scenario: textures from the seed, platform pose and lighting from
/// draw_layout().
Scene build_scene(const Scenario& scenario, uint64_t seed);

}  // namespace alight::sim
