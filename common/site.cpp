#include "common/site.hpp"

#include <algorithm>
#include <cstdio>

#include "common/params.hpp"

namespace alight {

bool narrow_to_site(const SiteArea& site, double inset_m, double min_span_m, Vector3d& fence_min,
                    Vector3d& fence_max) {
  Vector3d lo = fence_min, hi = fence_max;
  lo.head<2>() = lo.head<2>().cwiseMax(site.min_xy_m() + Vector2d::Constant(inset_m));
  hi.head<2>() = hi.head<2>().cwiseMin(site.max_xy_m() - Vector2d::Constant(inset_m));
  hi.z() = std::min(hi.z(), site.height_m - inset_m);
  if (!((hi - lo).minCoeff() > min_span_m)) return false;
  fence_min = lo;
  fence_max = hi;
  return true;
}

std::string fence_text(const Vector3d& lo, const Vector3d& hi, const std::string& site_file) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "[%.2f %.2f %.2f] .. [%.2f %.2f %.2f] m", lo.x(), lo.y(), lo.z(),
                hi.x(), hi.y(), hi.z());
  return std::string(buf) + (site_file.empty() ? "" : " (the site " + site_file + ")");
}

std::string site_text(const SiteArea& s) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "size_m [%g, %g] around [%g, %g], height_m %g", s.size_m.x(),
                s.size_m.y(), s.center_xy_m.x(), s.center_xy_m.y(), s.height_m);
  return buf;
}

SiteArea load_site(const std::string& path) {
  const ParamNode root = ParamNode::load_file(path);
  const ParamNode area = root.child("area");
  SiteArea s;
  area.require("size_m", s.size_m);
  area.check(s.size_m.minCoeff() > 0, "size_m", "must be positive on both axes");
  area.require("center_xy_m", s.center_xy_m);
  area.require("height_m", s.height_m);
  area.check(s.height_m > 0, "height_m", "must be positive (the ceiling above the floor)");
  return s;
}

}  // namespace alight
