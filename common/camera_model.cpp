#include "common/camera_model.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>

#include "common/params.hpp"

namespace alight {

CameraModel CameraModel::firefly_mv_4mm() { return CameraModel{}; }

Matrix3d CameraModel::K() const {
  Matrix3d K;
  K << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return K;
}

bool CameraModel::has_distortion() const {
  if (distortion == Distortion::kEquidistant) return true;
  for (double d : D)
    if (d != 0.0) return true;
  return false;
}

namespace {
// Equidistant: theta_d(theta) and its derivative.
double fisheye_theta_d(const std::array<double, 5>& k, double th) {
  const double t2 = th * th;
  return th * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
}
double fisheye_dtheta_d(const std::array<double, 5>& k, double th) {
  const double t2 = th * th;
  return 1.0 + t2 * (3 * k[0] + t2 * (5 * k[1] + t2 * (7 * k[2] + t2 * 9 * k[3])));
}
}  // namespace

Vector2d CameraModel::distort(const Vector2d& xn) const {
  if (distortion == Distortion::kEquidistant) {
    const double r = xn.norm();
    if (r < 1e-12) return xn;
    return xn * (fisheye_theta_d(D, std::atan(r)) / r);
  }
  const double x = xn.x(), y = xn.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (D[0] + r2 * (D[1] + r2 * D[4]));
  return Vector2d(x * radial + 2.0 * D[2] * x * y + D[3] * (r2 + 2.0 * x * x),
                  y * radial + D[2] * (r2 + 2.0 * y * y) + 2.0 * D[3] * x * y);
}

Vector2d CameraModel::undistort(const Vector2d& xd) const {
  if (!has_distortion()) return xd;
  if (distortion == Distortion::kEquidistant) {
    // Newton on theta_d(theta) = |xd| from theta = |xd|; the normalised point is tan(theta)
    // along xd (as cv::fisheye::undistortPoints).
    const double rd = xd.norm();
    if (rd < 1e-12) return xd;
    double th = std::min(rd, 0.5 * M_PI - 1e-6);
    for (int i = 0; i < 20; ++i) {
      const double step = (fisheye_theta_d(D, th) - rd) / fisheye_dtheta_d(D, th);
      th = std::clamp(th - step, 0.0, 0.5 * M_PI - 1e-6);
      if (std::abs(step) < 1e-14) break;
    }
    return xd * (std::tan(th) / rd);
  }
  Vector2d xn = xd;
  for (int i = 0; i < 20; ++i) {
    const Vector2d err = distort(xn) - xd;
    xn -= err;
    if (err.squaredNorm() < 1e-24) break;
  }
  return xn;
}

std::optional<Vector2d> CameraModel::project(const Vector3d& p_C) const {
  if (p_C.z() <= 1e-9) return std::nullopt;
  const Vector2d xd = distort(Vector2d(p_C.x() / p_C.z(), p_C.y() / p_C.z()));
  return Vector2d(fx * xd.x() + cx, fy * xd.y() + cy);
}

Vector3d CameraModel::ray(const Vector2d& pixel) const {
  const Vector2d xn = undistort(Vector2d((pixel.x() - cx) / fx, (pixel.y() - cy) / fy));
  return Vector3d(xn.x(), xn.y(), 1.0);
}

bool CameraModel::in_image(const Vector2d& px, double margin) const {
  return px.x() >= -0.5 + margin && px.y() >= -0.5 + margin && px.x() <= width - 0.5 - margin &&
         px.y() <= height - 0.5 - margin;
}

void CameraModel::validate() const {
  param_check(width > 0, "image_width", width, "must be > 0");
  param_check(height > 0, "image_height", height, "must be > 0");
  param_check(fx > 0 && std::isfinite(fx), "camera_matrix.data[0]", fx, "fx must be > 0");
  param_check(fy > 0 && std::isfinite(fy), "camera_matrix.data[4]", fy, "fy must be > 0");
  param_check(cx > 0 && cx < width, "camera_matrix.data[2]", cx, "cx must lie inside the image");
  param_check(cy > 0 && cy < height, "camera_matrix.data[5]", cy, "cy must lie inside the image");
  param_check(distortion != Distortion::kEquidistant || D[4] == 0.0,
              "distortion_coefficients.data[4]", D[4], "equidistant has four coefficients");
}

namespace {
std::vector<double> matrix_data(const ParamNode& root, const std::string& key, int rows, int cols) {
  const ParamNode m = root.child(key);
  int r = 0, c = 0;
  m.require("rows", r);
  m.require("cols", c);
  std::vector<double> data;
  m.require("data", data);
  if (r * c != static_cast<int>(data.size()))
    throw m.error(
        "data", m.value_text("data"),
        "has " + std::to_string(data.size()) + " numbers, rows x cols = " + std::to_string(r * c));
  if (rows > 0 && (r != rows || c != cols))
    throw root.error(key, root.value_text(key),
                     "must be " + std::to_string(rows) + "x" + std::to_string(cols));
  m.finish();
  return data;
}
}  // namespace

CameraModel load_camera_info(const std::string& path) {
  const ParamNode root = ParamNode::load_file(path);
  CameraModel cam;
  root.require("image_width", cam.width);
  root.require("image_height", cam.height);
  root.read("camera_name", cam.name);
  const auto K = matrix_data(root, "camera_matrix", 3, 3);
  cam.fx = K[0];
  cam.cx = K[2];
  cam.fy = K[4];
  cam.cy = K[5];
  root.check(K[1] == 0.0 && K[3] == 0.0 && K[6] == 0.0 && K[7] == 0.0 && K[8] == 1.0,
             "camera_matrix", "must be [fx 0 cx; 0 fy cy; 0 0 1]");
  std::string model = "plumb_bob";
  root.read("distortion_model", model);
  if (model != "plumb_bob" && model != "none" && model != "equidistant")
    throw root.error("distortion_model", model, "must be plumb_bob, equidistant (fisheye) or none");
  if (model == "equidistant") {
    cam.distortion = CameraModel::Distortion::kEquidistant;
    const auto D = matrix_data(root, "distortion_coefficients", -1, -1);
    if (D.size() != 4)
      throw root.error("distortion_coefficients", root.value_text("distortion_coefficients"),
                       "equidistant needs 4 coefficients (k1 k2 k3 k4)");
    for (size_t i = 0; i < D.size(); ++i) cam.D[i] = D[i];
  }
  if (model == "plumb_bob" && root.has("distortion_coefficients")) {
    const auto D = matrix_data(root, "distortion_coefficients", -1, -1);
    if (D.size() != 5 && D.size() != 4 && !D.empty())
      throw root.error("distortion_coefficients", root.value_text("distortion_coefficients"),
                       "plumb_bob needs 5 coefficients (k1 k2 p1 p2 k3)");
    for (size_t i = 0; i < D.size(); ++i) cam.D[i] = D[i];
  }
  // Rectification and projection matrices are part of the layout but unused for a mono camera.
  root.optional_child("rectification_matrix");
  root.optional_child("projection_matrix");
  root.finish();
  root.validate(cam);
  return cam;
}

std::string camera_info_yaml(const CameraModel& cam) {
  YAML::Emitter out;
  out.SetDoublePrecision(10);
  auto matrix = [&](const char* key, int rows, int cols, const std::vector<double>& data) {
    out << YAML::Key << key << YAML::Value << YAML::BeginMap << YAML::Key << "rows" << YAML::Value
        << rows << YAML::Key << "cols" << YAML::Value << cols << YAML::Key << "data" << YAML::Value
        << YAML::Flow << data << YAML::EndMap;
  };
  out << YAML::BeginMap;
  out << YAML::Key << "image_width" << YAML::Value << cam.width;
  out << YAML::Key << "image_height" << YAML::Value << cam.height;
  out << YAML::Key << "camera_name" << YAML::Value << cam.name;
  matrix("camera_matrix", 3, 3, {cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1});
  const bool fisheye = cam.distortion == CameraModel::Distortion::kEquidistant;
  out << YAML::Key << "distortion_model" << YAML::Value << (fisheye ? "equidistant" : "plumb_bob");
  if (fisheye)
    matrix("distortion_coefficients", 1, 4, {cam.D.begin(), cam.D.begin() + 4});
  else
    matrix("distortion_coefficients", 1, 5, {cam.D.begin(), cam.D.end()});
  matrix("rectification_matrix", 3, 3, {1, 0, 0, 0, 1, 0, 0, 0, 1});
  matrix("projection_matrix", 3, 4, {cam.fx, 0, cam.cx, 0, 0, cam.fy, cam.cy, 0, 0, 0, 1, 0});
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

void save_camera_info(const std::string& path, const CameraModel& cam) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot write the camera_info file");
  f << camera_info_yaml(cam);
}

}  // namespace alight
