#include "sim/scene.hpp"

#include <cmath>
#include <random>

namespace alight::sim {

bool Scene::near_opening_frame(const Vector3d& p_W) const {
  if (!opening) return false;
  const Vector3d d = p_W - opening->center_W;
  // The wall faces -x, so the opening spans world y (width) and z (height).
  const double dy = std::abs(d.y()) - 0.5 * opening->size_m.x();
  const double dz = std::abs(d.z()) - 0.5 * opening->size_m.y();
  return std::max(dy, dz) < frame_margin_m;
}

Scene build_scene(const Scenario& sc, uint64_t seed) {
  Scene scene;
  std::mt19937_64 rng(seed ^ 0x5CE7E5CE7EULL);
  std::uniform_real_distribution<double> sym(-1.0, 1.0);

  scene.lighting = sc.lighting;
  scene.lighting.gain *= 1.0 + sc.randomize.light_gain * sym(rng);

  scene.textures.push_back(Texture::make(sc.floor_texture, seed));
  scene.floor_texture = 0;

  if (sc.platform) {
    const PlatformParams& p = *sc.platform;
    Box b;
    b.kind = Box::Kind::kPlatform;
    const Vector2d xy = p.center_xy_m + sc.randomize.platform_xy_m * Vector2d(sym(rng), sym(rng));
    b.set_yaw((p.yaw_deg + sc.randomize.platform_yaw_deg * sym(rng)) * M_PI / 180.0);
    b.half_size_m = 0.5 * p.size_m;
    b.center_W = Vector3d(xy.x(), xy.y(), 0.5 * p.size_m.z());
    b.texture = static_cast<int>(scene.textures.size());
    scene.textures.push_back(Texture::make(p.texture, seed));
    scene.boxes.push_back(b);
    scene.platform = PlatformTruth{Vector3d(xy.x(), xy.y(), p.size_m.z()), p.size_m, b.yaw_rad()};
  }

  if (sc.wall) {
    const WallParams& w = *sc.wall;
    scene.has_wall = true;
    const int wall_tex = static_cast<int>(scene.textures.size());
    scene.textures.push_back(Texture::make(w.texture, seed));
    const int room_tex = static_cast<int>(scene.textures.size());
    scene.textures.push_back(Texture::make(w.room_texture, seed));
    const double y0 = w.center_y_m - 0.5 * w.width_m, y1 = w.center_y_m + 0.5 * w.width_m;
    auto add = [&](Box::Kind kind, double xa, double xb, double ya, double yb, double za,
                   double zb, int tex) {
      if (xb - xa <= 1e-6 || yb - ya <= 1e-6 || zb - za <= 1e-6) return;
      Box b;
      b.kind = kind;
      b.center_W = Vector3d(0.5 * (xa + xb), 0.5 * (ya + yb), 0.5 * (za + zb));
      b.half_size_m = Vector3d(0.5 * (xb - xa), 0.5 * (yb - ya), 0.5 * (zb - za));
      b.texture = tex;
      scene.boxes.push_back(b);
    };
    const double xa = w.x_m, xb = w.x_m + w.thickness_m;
    if (w.has_opening) {
      const double oy0 = w.opening_center_yz_m.x() - 0.5 * w.opening_size_m.x();
      const double oy1 = w.opening_center_yz_m.x() + 0.5 * w.opening_size_m.x();
      const double oz0 = w.opening_center_yz_m.y() - 0.5 * w.opening_size_m.y();
      const double oz1 = w.opening_center_yz_m.y() + 0.5 * w.opening_size_m.y();
      add(Box::Kind::kWall, xa, xb, y0, oy0, 0, w.height_m, wall_tex);    // left of the opening
      add(Box::Kind::kWall, xa, xb, oy1, y1, 0, w.height_m, wall_tex);    // right
      add(Box::Kind::kWall, xa, xb, oy0, oy1, 0, oz0, wall_tex);          // below
      add(Box::Kind::kWall, xa, xb, oy0, oy1, oz1, w.height_m, wall_tex); // above
      scene.opening = OpeningTruth{Vector3d(xa, w.opening_center_yz_m.x(), w.opening_center_yz_m.y()),
                                   w.opening_size_m, -Vector3d::UnitX()};
    } else {
      add(Box::Kind::kWall, xa, xb, y0, y1, 0, w.height_m, wall_tex);
    }
    // The room behind: back wall, side walls and ceiling, seen through the opening.
    const double back = w.x_m + w.room_depth_m, t = 0.1;
    add(Box::Kind::kRoom, back, back + t, y0, y1, 0, w.height_m, room_tex);
    add(Box::Kind::kRoom, xb, back, y0 - t, y0, 0, w.height_m, room_tex);
    add(Box::Kind::kRoom, xb, back, y1, y1 + t, 0, w.height_m, room_tex);
    add(Box::Kind::kRoom, xb, back + t, y0 - t, y1 + t, w.height_m, w.height_m + t, room_tex);
  }
  return scene;
}

}  // namespace alight::sim
