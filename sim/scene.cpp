#include "sim/scene.hpp"

#include <cmath>
#include <limits>
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

std::optional<RayHit> Scene::cast_ray(const Vector3d& origin_W, const Vector3d& dir_W,
                                      double max_distance_m) const {
  const double len = dir_W.norm();
  if (!origin_W.allFinite() || !(len > 0) || !std::isfinite(len) || !(max_distance_m >= 0))
    return std::nullopt;
  const Vector3d d = dir_W / len;
  std::optional<RayHit> best;
  auto take = [&](double t, const Vector3d& n, int box) {
    if (t <= max_distance_m && (!best || t < best->distance_m)) best = RayHit{t, n, box};
  };

  if (origin_W.z() < 0.0)
    take(0.0, -d, -1);
  else if (d.z() < 0.0)
    take(-origin_W.z() / d.z(), Vector3d::UnitZ(), -1);

  for (size_t i = 0; i < boxes.size(); ++i) {
    const Box& b = boxes[i];
    const Vector3d o = b.to_local(origin_W);
    const Vector3d u = b.R_WO().transpose() * d;
    // Entry and exit along the ray through the three slabs; the entry's axis is the face hit.
    double t_in = -std::numeric_limits<double>::infinity();
    double t_out = std::numeric_limits<double>::infinity();
    int axis = -1;
    bool miss = false;
    for (int k = 0; k < 3 && !miss; ++k) {
      const double h = b.half_size_m[k];
      if (u[k] == 0.0) {
        miss = std::abs(o[k]) > h;  // parallel to the slab and outside it
        continue;
      }
      double t0 = (-h - o[k]) / u[k], t1 = (h - o[k]) / u[k];
      if (t0 > t1) std::swap(t0, t1);
      if (t0 > t_in) {
        t_in = t0;
        axis = k;
      }
      t_out = std::min(t_out, t1);
    }
    if (miss || t_in > t_out || t_out <= 0.0) continue;
    if (t_in <= 0.0 || axis < 0) {  // the origin is inside (or on) the box
      take(0.0, -d, static_cast<int>(i));
      continue;
    }
    Vector3d n_O = Vector3d::Zero();
    n_O[axis] = u[axis] > 0 ? -1.0 : 1.0;
    take(t_in, b.R_WO() * n_O, static_cast<int>(i));
  }
  return best;
}

SeededLayout draw_layout(const Scenario& sc, uint64_t seed) {
  SeededLayout out;
  // The draws of brightness and platform come first and in this order, so that seeds whose first
  // placement was already clear of the start keep the scene they always had.
  std::mt19937_64 rng(seed ^ 0x5CE7E5CE7EULL);
  std::uniform_real_distribution<double> sym(-1.0, 1.0);
  out.lighting = sc.lighting;
  out.lighting.gain *= 1.0 + sc.randomize.light_gain * sym(rng);

  if (sc.platform) {
    const PlatformParams& p = *sc.platform;
    const RandomizeParams& r = sc.randomize;
    out.platform_center_xy_m = p.center_xy_m;
    out.platform_yaw_rad = p.yaw_deg * M_PI / 180.0;
    if (r.platform_xy_m > 0 || r.platform_yaw_deg > 0) {
      // Rejection keeps the placements uniform over the clear part of the range.
      for (int attempt = 0; attempt < 1000; ++attempt) {
        const Vector2d xy = p.center_xy_m + r.platform_xy_m * Vector2d(sym(rng), sym(rng));
        const double yaw = (p.yaw_deg + r.platform_yaw_deg * sym(rng)) * M_PI / 180.0;
        if (footprint_distance_m(p, xy, yaw, sc.start_position_m.head<2>()) >=
            r.start_clearance_m) {
          out.platform_center_xy_m = xy;
          out.platform_yaw_rad = yaw;
          break;
        }
      }
    }
  }

  // Lighting variation from a stream of its own: it leaves the draws above as they were.
  std::mt19937_64 light_rng(seed ^ 0x11647ULL * 0x9E3779B97F4A7C15ULL);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  LightingParams& l = out.lighting;
  const double turn = sc.randomize.light_dir_deg * (2.0 * unit(light_rng) - 1.0) * M_PI / 180.0;
  l.light_dir_W = rotation_from_rpy(0, 0, turn) * l.light_dir_W;
  if (sc.randomize.light_falloff > 0) {
    l.falloff = sc.randomize.light_falloff * unit(light_rng);
    const Vector2d u(unit(light_rng) - 0.5, unit(light_rng) - 0.5);
    const Vector2d xy = sc.area_center_xy_m + sc.area_size_m.cwiseProduct(u);
    l.lamp_W = Vector3d(xy.x(), xy.y(), l.lamp_W.z());
  }
  return out;
}

Scene build_scene(const Scenario& sc, uint64_t seed) {
  Scene scene;
  const SeededLayout layout = draw_layout(sc, seed);
  scene.lighting = layout.lighting;

  scene.textures.push_back(Texture::make(sc.floor_texture, seed));
  scene.floor_texture = 0;
  for (const auto& c : scene.lighting.casters) {
    Box b;
    b.half_size_m = 0.5 * Vector3d(c[2], c[3], c[4]);
    b.center_W = Vector3d(c[0], c[1], 0.5 * c[4]);
    b.set_yaw(c[5] * M_PI / 180.0);
    scene.shadow_casters.push_back(b);
  }

  if (sc.platform) {
    const PlatformParams& p = *sc.platform;
    Box b;
    b.kind = Box::Kind::kPlatform;
    const Vector2d xy = layout.platform_center_xy_m;
    b.set_yaw(layout.platform_yaw_rad);
    b.half_size_m = 0.5 * p.size_m;
    b.center_W = Vector3d(xy.x(), xy.y(), 0.5 * p.size_m.z());
    b.texture = static_cast<int>(scene.textures.size());
    scene.textures.push_back(Texture::make(p.texture, seed));
    if (p.reflective) {
      b.reflectance = p.reflection.reflectance;
      scene.sky_texture = static_cast<int>(scene.textures.size());
      scene.textures.push_back(Texture::make(p.reflection.sky, seed));
      scene.sky_z_m = p.size_m.z() + p.reflection.sky_height_m;
    }
    scene.platform_box = static_cast<int>(scene.boxes.size());
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
    auto add = [&](Box::Kind kind, double xa, double xb, double ya, double yb, double za, double zb,
                   int tex) {
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
      add(Box::Kind::kWall, xa, xb, y0, oy0, 0, w.height_m, wall_tex);     // left of the opening
      add(Box::Kind::kWall, xa, xb, oy1, y1, 0, w.height_m, wall_tex);     // right
      add(Box::Kind::kWall, xa, xb, oy0, oy1, 0, oz0, wall_tex);           // below
      add(Box::Kind::kWall, xa, xb, oy0, oy1, oz1, w.height_m, wall_tex);  // above
      scene.opening =
          OpeningTruth{Vector3d(xa, w.opening_center_yz_m.x(), w.opening_center_yz_m.y()),
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
