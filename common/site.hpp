#pragma once
// The site: the room a flight may use (a motion-capture volume, a hall, a yard), an upright box
// in the world frame with its floor at z = 0. A vehicle file's geofences are the vehicle's own;
// the site narrows them to the room flown in that day, as a fence set per site does on PX4 or
// ArduPilot, and never widens them. A file holds it as an `area:` section (size_m, center_xy_m,
// height_m); a simulator scenario is such a file, its `area:` being the room the simulator flies
// in, so the simulated flights take their fence from the scenario they fly.

#include <string>

#include "common/geometry.hpp"

namespace alight {

struct SiteArea {
  Vector2d size_m = Vector2d(6.0, 6.0);  ///< x, y extent [m]
  Vector2d center_xy_m = Vector2d::Zero();
  double height_m = 4.0;  ///< its ceiling above the floor [m]

  Vector2d min_xy_m() const { return center_xy_m - 0.5 * size_m; }
  Vector2d max_xy_m() const { return center_xy_m + 0.5 * size_m; }
};

/// Narrows the box `fence_min`..`fence_max` to lie `inset_m` inside the site's walls and ceiling
/// (its floor is left as it is). Returns false, and leaves the box as it was, when the narrowed
/// box would span `min_span_m` or less on an axis (the site and the box hardly overlap).
bool narrow_to_site(const SiteArea& site, double inset_m, double min_span_m, Vector3d& fence_min,
                    Vector3d& fence_max);

/// "[x y z] .. [x y z] m" (centimetres), and " (the site FILE)" when `site_file` is not empty:
/// the geofence in force, as the nodes log it at start.
std::string fence_text(const Vector3d& fence_min, const Vector3d& fence_max,
                       const std::string& site_file);

/// "size_m [x, y] around [x, y], height_m h": a site in an error message.
std::string site_text(const SiteArea& site);

/// Reads the `area:` section of `path` (size_m, center_xy_m and height_m, all required and
/// positive where they are extents). The file's other sections and the area's other keys (a
/// scenario's floor texture) are the simulator's and are not read. Throws ParamError naming the
/// file and the key.
SiteArea load_site(const std::string& path);

}  // namespace alight
