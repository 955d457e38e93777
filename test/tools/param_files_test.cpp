// Every configuration file through alight-params (issue 18): the dump of each shipped file loads
// back through the real loaders to the same parameters, every bounded parameter is refused just
// outside its range at its full dotted key, and the tool exits 2 naming file, key and value.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include "common/build_paths.hpp"
#include "common/params.hpp"
#include "tools/param_dump.hpp"

namespace alight::tools {
namespace {

namespace fs = std::filesystem;

const fs::path kConfig = fs::path(alight::build::source_dir()) / "config";

fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::path(alight::build::binary_dir()) / "test_tmp" / "param_files" / name;
  fs::create_directories(dir);
  return dir;
}

std::string write(const fs::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path.string();
}

// The dump without its first line, which names the file it was made from.
std::string body(const std::string& dump) { return dump.substr(dump.find('\n') + 1); }

// The shipped files of each kind (config/cameras also holds camera_info intrinsics files, which
// are OpenCV's format, not alight-camera's).
std::map<std::string, std::vector<fs::path>> shipped_files() {
  std::map<std::string, std::vector<fs::path>> out;
  const std::map<std::string, std::string> folders = {{"vehicles", "vehicle"},
                                                      {"scenarios", "scenario"},
                                                      {"cameras", "camera"},
                                                      {"mocap", "mocap"},
                                                      {"autopilot", "autopilot"}};
  for (const auto& [folder, kind] : folders) {
    for (const auto& entry : fs::recursive_directory_iterator(kConfig / folder)) {
      if (entry.path().extension() != ".yaml") continue;
      if (kind == "camera" && YAML::LoadFile(entry.path().string())["camera_matrix"]) continue;
      out[kind].push_back(entry.path());
    }
    std::sort(out[kind].begin(), out[kind].end());
  }
  return out;
}

TEST(ParamFilesTest, EveryShippedFileDumpsToYamlThatLoadsBackToTheSameParameters) {
  const auto files = shipped_files();
  EXPECT_EQ(files.at("vehicle").size(), 2u);
  EXPECT_EQ(files.at("scenario").size(), 11u);  // with estimator_drift and the moving platforms
  EXPECT_EQ(files.at("camera").size(), 2u);
  EXPECT_EQ(files.at("mocap").size(), 2u);
  EXPECT_EQ(files.at("autopilot").size(), 8u);  // with sitl/
  const fs::path dir = temp_dir("round_trip");
  for (const auto& [kind, paths] : files) {
    for (const auto& path : paths) {
      SCOPED_TRACE(path.string());
      const std::string dump = dump_params(kind, path.string());
      const std::string again = write(dir / (kind + "_" + path.filename().string()), dump);
      EXPECT_EQ(body(dump_params(kind, again)), body(dump)) << dump;
    }
  }
}

TEST(ParamFilesTest, TheDefaultsOfEveryKindLoadBackToTheDefaults) {
  const fs::path dir = temp_dir("defaults");
  for (const auto& kind : param_file_kinds()) {
    SCOPED_TRACE(kind);
    const std::string dump = dump_params(kind, "");
    const std::string file = write(dir / (kind + ".yaml"), dump);
    for (const auto& section : param_sections(kind, "")) {
      if (section.key.rfind("cameras.", 0) == 0) continue;  // no default camera: an example
      if (kind == "mocap") {  // a room has no default server: the one required key without one
        try {
          section.load(file);
          ADD_FAILURE() << "a mocap file without a tracker loaded";
        } catch (const ParamError& e) {
          EXPECT_EQ(e.key(), "mocap.server.tracker") << e.what();
        }
        continue;
      }
      const auto defaults = section.load("");
      const auto loaded = section.load(file);
      ASSERT_EQ(loaded.params.size(), defaults.params.size());
      for (size_t i = 0; i < defaults.params.size(); ++i) {
        // A relative default path comes back resolved against the file it was written to.
        if (defaults.params[i].rule.find("path") != std::string::npos) continue;
        EXPECT_EQ(loaded.params[i].value, defaults.params[i].value)
            << section.key << "." << defaults.params[i].key;
      }
    }
  }
}

TEST(ParamFilesTest, EveryParameterIsDumpedWithItsMeaningAndTheVisionSectionEvenWhenAbsent) {
  const std::string dump = dump_params("vehicle", (kConfig / "vehicles/pelican.yaml").string());
  EXPECT_NE(dump.find("\nvision:\n"), std::string::npos);
  EXPECT_NE(dump.find("    # adaptive stopping: probability of one all-inlier sample; in (0, 1)\n"
                      "    confidence: 0.995\n"),
            std::string::npos)
      << dump;
  for (const auto& kind : param_file_kinds()) {
    std::istringstream lines(dump_params(kind, ""));
    for (std::string line; std::getline(lines, line);)
      if (line.find("# ") != std::string::npos) {
        EXPECT_LE(line.size(), 100u) << line;
      }
  }
  for (const auto& kind : param_file_kinds())
    for (const auto& section : param_sections(kind, ""))
      for (const auto& p : section.load("").params)
        EXPECT_FALSE(p.doc.empty()) << kind << ": " << section.key << "." << p.key;
}

// --- Property: a value just outside a declared range is refused at its full key ----------------

// The number just outside one end of `range` (the end itself when it is open).
std::string just_outside(const ParamInfo& p, bool upper) {
  const double bound = upper ? *p.range.hi() : *p.range.lo();
  const bool closed = upper ? p.range.hi_closed() : p.range.lo_closed();
  if (p.integer) {
    const long long b = std::llround(bound);
    return std::to_string(closed ? (upper ? b + 1 : b - 1) : b);
  }
  const double step = 1e-6 * std::max(1.0, std::abs(bound));
  return param_detail::number_text(closed ? (upper ? bound + step : bound - step) : bound);
}

std::vector<std::string> split_key(const std::string& key) {
  std::vector<std::string> parts;
  std::stringstream in(key);
  for (std::string part; std::getline(in, part, '.');) parts.push_back(part);
  return parts;
}

// The node at dotted `key` of `doc` (invalid when a part is missing).
YAML::Node at(YAML::Node doc, const std::string& key) {
  YAML::Node n = doc;
  for (const auto& part : split_key(key)) {
    if (!n.IsMap() || !n[part]) return YAML::Node(YAML::NodeType::Undefined);
    n.reset(n[part]);
  }
  return n;
}

std::string emit(const YAML::Node& doc) {
  YAML::Emitter out;
  out << doc;
  return std::string(out.c_str()) + "\n";
}

TEST(ParamFilesProperty, AValueJustOutsideItsRangeIsReportedAtItsFullKeyWithTheValueWritten) {
  // Base files in which every section is present (the dump fills in every key).
  const std::map<std::string, std::vector<fs::path>> bases = {
      {"vehicle", {kConfig / "vehicles/pelican.yaml"}},
      {"scenario", {kConfig / "scenarios/landing_a.yaml", kConfig / "scenarios/ingress.yaml"}},
      {"camera", {kConfig / "cameras/usb_mono_640x480.yaml"}},
      {"station", {""}},
      {"mocap", {kConfig / "mocap/optitrack_motive.yaml"}},
      {"autopilot", {kConfig / "autopilot/px4.yaml"}}};
  const fs::path dir = temp_dir("ranges");
  std::set<std::string> tested;
  int cases = 0;
  for (const auto& [kind, files] : bases) {
    for (const auto& base_file : files) {
      const YAML::Node base = YAML::Load(dump_params(kind, base_file.string()));
      for (const auto& section : param_sections(kind, base_file.string())) {
        for (const auto& p : section.load(base_file.string()).params) {
          const std::string key = section.key.empty() ? p.key : section.key + "." + p.key;
          // Absent in this base: in a commented-out optional section.
          if (!at(base, key).IsDefined() || tested.count(kind + " " + key)) continue;
          for (const bool upper : {false, true}) {
            if (!(upper ? p.range.hi() : p.range.lo())) continue;
            tested.insert(kind + " " + key);
            const std::string bad = just_outside(p, upper);
            YAML::Node doc = YAML::Clone(base);
            YAML::Node node = at(doc, key);
            // A list: its first number out of range.
            std::string expected = bad;
            if (node.IsSequence()) {
              node[0] = YAML::Load(bad);
              expected = "[" + bad;
              for (size_t i = 1; i < node.size(); ++i)
                expected += ", " + param_detail::number_text(node[i].as<double>());
              expected += "]";
            } else {
              node = YAML::Load(bad);
            }
            const std::string file =
                write(dir / (kind + "_" + key + (upper ? "_hi" : "_lo") + ".yaml"), emit(doc));
            ++cases;
            try {
              section.load(file);
              ADD_FAILURE() << key << " = " << bad << " accepted (" << p.rule << ")";
            } catch (const ParamError& e) {
              EXPECT_EQ(e.key(), key) << bad << ": " << e.what();
              EXPECT_EQ(e.value(), expected) << e.what();
              EXPECT_EQ(e.file(), file);
            }
          }
        }
      }
    }
  }
  // Every component's bounded parameters were reached (not a vacuous pass).
  for (const char* key :
       {"vehicle cameras.downward.rpy_offset_deg", "vehicle vehicle.mass_kg",
        "vehicle outer_loop.pose_lost_s", "vehicle autonomy.refinement.n_min",
        "vehicle autonomy.restart.state_max_age_s", "vehicle vision.align.max_iterations",
        "vehicle vision.star.max_size", "vehicle vision.poses.history_s",
        "vehicle vision.max_pose_wait_s", "scenario sim.physics_dt_s", "scenario platform.size_m",
        "scenario wall.opening.size_m", "scenario wall.room_texture.size_px",
        "scenario area.floor_texture.mean", "scenario mocap.rate_hz", "camera backoff_max_s",
        "station ground_station.max_payload_bytes", "mocap mocap.velocity.span_s",
        "autopilot mavlink.stream_rate_hz"})
    EXPECT_TRUE(tested.count(key)) << key;
  EXPECT_GT(cases, 250);
  std::cout << cases << " values out of range over " << tested.size() << " bounded keys\n";
}

// --- The tool --------------------------------------------------------------------------------

struct ToolRun {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

ToolRun run(const std::string& args) {
  ToolRun r;
  FILE* pipe =
      ::popen((alight::build::program("alight-params") + " " + args + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf{};
  for (size_t n; (n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0;)
    r.output.append(buf.data(), n);
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

TEST(AlightParamsTest, ABadFileExitsTwoNamingFileKeyAndValue) {
  const std::string file = write(temp_dir("tool") / "bad_vehicle.yaml",
                                 "outer_loop: {mass_kg: 1.0, geofence_min_W_m: [-3, -3, -0.5], "
                                 "geofence_max_W_m: [4.7, 3, 2.6]}\nautonomy:\n  failsafe:\n"
                                 "    pose_lost_s: 12\nvehicle: {}\n");
  const ToolRun r = run("--dump " + file);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(file + ": autonomy.failsafe.pose_lost_s = 12: must be <= 10 s"),
            std::string::npos)
      << r.output;
  const ToolRun scenario = run("--dump " + file + " --kind scenario");
  EXPECT_EQ(scenario.exit_code, 2);
  EXPECT_NE(scenario.output.find(file + ": name = <missing>: required key is missing"),
            std::string::npos)
      << scenario.output;
  EXPECT_EQ(run("--defaults airship").exit_code, 2);
  EXPECT_EQ(run("").exit_code, 2);
}

TEST(AlightParamsTest, PrintsTheDumpOfAFileAndTheDefaultsOfEachKind) {
  const std::string vehicle = (kConfig / "vehicles/starmac.yaml").string();
  const ToolRun r = run("--dump " + vehicle);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, dump_params("vehicle", vehicle));
  for (const auto& kind : param_file_kinds()) {
    const ToolRun d = run("--defaults " + kind);
    EXPECT_EQ(d.exit_code, 0) << kind << ": " << d.output;
    EXPECT_EQ(d.output, dump_params(kind, "")) << kind;
  }
}

TEST(AlightParamsTest, ChecksManyFilesInOneRunAndStopsAtTheFirstBadOneNamingIt) {
  const std::string a = (kConfig / "scenarios/landing_a.yaml").string();
  const std::string b = (kConfig / "scenarios/ingress.yaml").string();
  const ToolRun good = run("--check " + a + " " + b + " --kind scenario");
  EXPECT_EQ(good.exit_code, 0) << good.output;
  EXPECT_EQ(good.output, "2 scenario files read\n");
  const std::string bad = write(temp_dir("tool_check") / "no_name.yaml", "seed: 1\n");
  const ToolRun r = run("--check " + a + " " + bad + " " + b + " --kind scenario");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(bad + ": name = <missing>: required key is missing"), std::string::npos)
      << r.output;
  EXPECT_EQ(run("--check " + a + " --dump " + a).exit_code, 2);
}

}  // namespace
}  // namespace alight::tools
