#include "tools/param_dump.hpp"

#include <filesystem>
#include <sstream>

#include "autonomy/params.hpp"
#include "camera_driver/params.hpp"
#include "common/camera_mount.hpp"
#include "ground_station/params.hpp"
#include "mavlink/bridge_params.hpp"
#include "mocap/params.hpp"
#include "outer_loop/params.hpp"
#include "sim/params.hpp"
#include "vision/params.hpp"

namespace alight::tools {

namespace {

int depth(const std::string& key) {
  if (key.empty()) return 0;
  int d = 1;
  for (const char c : key) d += c == '.';
  return d;
}

template <class P>
ParamSection section(std::string key, std::string doc,
                     std::function<P(const std::string& file)> load) {
  ParamSection s{key, std::move(doc), nullptr};
  s.load = [key, load](const std::string& file) {
    const P p = file.empty() ? P{} : load(file);
    std::ostringstream yaml;
    P::schema().dump(yaml, p, 2 * depth(key));
    return ParamSection::Loaded{P::schema().params(p), yaml.str()};
  };
  return s;
}

ParamSection camera_section(const std::string& name) {
  return section<CameraMountParams>(
      "cameras." + name,
      "the camera `" + name +
          "` (common/camera_mount.hpp; paper eqs. 3 and 6): alight-sim, "
          "alight-vision",
      [name](const std::string& file) {
        return load_camera_mount_params(ParamNode::load_file(file), name);
      });
}

}  // namespace

const std::vector<std::string>& param_file_kinds() {
  static const std::vector<std::string> kinds = {"vehicle", "scenario", "camera",
                                                 "station", "mocap",    "autopilot"};
  return kinds;
}

std::vector<ParamSection> param_sections(const std::string& kind, const std::string& file) {
  std::vector<ParamSection> out;
  if (kind == "vehicle") {
    const std::vector<std::string> cameras = file.empty()
                                                 ? std::vector<std::string>{"downward"}
                                                 : camera_names(ParamNode::load_file(file));
    for (const auto& name : cameras) out.push_back(camera_section(name));
    out.push_back(section<sim::VehicleParams>(
        "vehicle", "physical model (sim/params.hpp): alight-sim",
        [](const std::string& f) { return sim::load_vehicle_params(f); }));
    out.push_back(section<outer_loop::OuterLoopParams>(
        "outer_loop", "position controller (paper 3.4, 4.1): alight-outer-loop",
        [](const std::string& f) { return outer_loop::load_params(f); }));
    out.push_back(section<autonomy::AutonomyParams>(
        "autonomy", "autonomy loop (paper 3.4): alight-autonomy",
        [](const std::string& f) { return autonomy::load_params(f); }));
    out.push_back(section<vision::NodeParams>(
        "vision", "vision (paper 3.1-3.3), optional in the file: alight-vision",
        [](const std::string& f) { return vision::load_node_params(f); }));
  } else if (kind == "scenario") {
    out.push_back(
        section<sim::Scenario>("", "a simulated world (sim/params.hpp): alight-sim --scenario",
                               [](const std::string& f) { return sim::load_scenario(f); }));
  } else if (kind == "camera") {
    out.push_back(section<camera::CameraParams>(
        "", "a camera (camera_driver/params.hpp): alight-camera --config",
        [](const std::string& f) { return camera::load_params(f); }));
  } else if (kind == "station") {
    out.push_back(section<ground_station::GroundStationParams>(
        "ground_station",
        "the operator's web page (ground_station/params.hpp): "
        "alight-ground-station --config",
        [](const std::string& f) { return ground_station::load_params(f); }));
  } else if (kind == "mocap") {
    out.push_back(section<mocap::MocapParams>(
        "mocap", "a motion-capture room (mocap/params.hpp): alight-mocap --config",
        [](const std::string& f) { return mocap::load_params(f); }));
  } else if (kind == "autopilot") {
    out.push_back(section<mavlink::BridgeParams>(
        "mavlink", "an autopilot over MAVLink (mavlink/bridge_params.hpp): alight-mavlink --config",
        [](const std::string& f) { return mavlink::load_bridge_params(f); }));
  } else {
    throw ParamError("", "--kind", kind,
                     "must be vehicle, scenario, camera, station, mocap or autopilot");
  }
  return out;
}

std::string dump_params(const std::string& kind, const std::string& file) {
  // Loaded by its absolute path, the file's relative paths resolve to absolute ones.
  const std::string path =
      file.empty() ? file : std::filesystem::absolute(file).lexically_normal().string();
  std::ostringstream out;
  try {
    out << "# " << (file.empty() ? "defaults of a " + kind + " file" : "parameters of " + file)
        << " (alight-params): every key with its meaning, constraint and unit\n";
    std::vector<std::string> open;  // the mappings the previous section opened
    for (const auto& s : param_sections(kind, path)) {
      const ParamSection::Loaded loaded = s.load(path);
      std::vector<std::string> keys;
      for (size_t at = 0; !s.key.empty();) {
        const size_t dot = s.key.find('.', at);
        keys.push_back(s.key.substr(at, dot == std::string::npos ? dot : dot - at));
        if (dot == std::string::npos) break;
        at = dot + 1;
      }
      std::ostringstream text;
      text << "\n";
      if (keys.empty()) text << "# " << s.doc << "\n";
      size_t same = 0;
      while (same < keys.size() - (keys.empty() ? 0 : 1) && same < open.size() &&
             open[same] == keys[same])
        ++same;
      for (size_t i = same; i < keys.size(); ++i) {
        if (i + 1 == keys.size()) text << std::string(2 * i, ' ') << "# " << s.doc << "\n";
        text << std::string(2 * i, ' ') << keys[i] << ":\n";
      }
      text << loaded.yaml;
      open = keys;
      // The defaults have no camera: the example is commented out.
      if (file.empty() && keys.size() > 1 && keys[0] == "cameras") {
        out << "\n# cameras: one section per camera, named by the scenario's camera.mount (no "
               "defaults; for example:)\n";
        param_detail::comment_out(out, text.str().substr(1), 0);
        open.clear();
      } else {
        out << text.str();
      }
    }
  } catch (const ParamError& e) {
    if (e.file() != path) throw;
    throw ParamError(file, e.key(), e.value(), e.problem());
  }
  return out.str();
}

}  // namespace alight::tools
