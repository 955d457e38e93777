// The vision's CPU time per frame, apart from the machine's load ("keep up with the
// camera"): for each scene (a family draw of scripts/scenes, or a scenario file) the flight of
// bench/vision/soak (soak_flight.hpp: a closed figure-eight in front of the wall's opening or
// over the platform, 60 Hz) is rendered once, and Pipeline::process runs on its frames in this
// process, --passes times over, as the soak publishes them over and over. Reported per scene and
// over all: the CPU time of this thread in Pipeline::process (CLOCK_THREAD_CPUTIME_ID: other
// processes on the core do not count) p50 / p90 / p99 / max, over every frame processed and over
// each frame's least of the passes (on a shared machine a neighbour that thrashes the caches or
// the core's other hyperthread slows runs of frames by half: the least is the frame's own cost,
// the same from run to run within a few percent); and, against the simulator's truth,
// how often an opening was found and its width, height and centre errors (p5 / p50 / p95), so a
// faster pipeline can be checked for accuracy on exactly the same frames. A digest of every
// frame's outcome tells whether two builds give the same output. A family joined to a camera
// effect (landing_photo+rolling_shutter) is rendered with it, and a rolling shutter's line delay
// reaches Pipeline::process with each frame, as the camera's driver stamps it.
//
//   build/bin/alight_vision_cpu_bench [--families ingress_photo,ingress_solid_photo]
//       [--seeds 1,2,3] [--scenario FILE ...] [--passes 2] [--standoff-m 2.0] [--loop-s 8]
//       [--vehicle config/vehicles/pelican.yaml] [--csv FILE] [--frames FILE]
//
// --csv writes one row per processed frame (scene, pass, frame, CPU ms, reason, errors).
// --frames writes every frame's whole result, exact and without timing (vision/frame_line.hpp),
// each line after its scene's name, so that two builds' outputs compare with diff.

#include <time.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "common/build_paths.hpp"
#include "common/heap.hpp"
#include "common/params.hpp"
#include "common/pose_buffer.hpp"
#include "soak_flight.hpp"
#include "support/stats.hpp"
#include "vision/frame_line.hpp"
#include "vision/params.hpp"
#include "vision/pipeline.hpp"

using namespace alight;
using alight::test::quantile;

namespace {

double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  size_t b = 0;
  while (b <= s.size()) {
    const size_t e = std::min(s.find(',', b), s.size());
    if (e > b) out.push_back(s.substr(b, e - b));
    b = e + 1;
  }
  return out;
}

struct Scene {
  std::string name, file;
  uint64_t seed = 1;
};

struct Stats {
  std::vector<double> cpu_ms, dw_m, dh_m, dc_m;
  std::vector<double> cpu_min_ms;  // each frame's least over the passes
  int frames = 0, found = 0, partial = 0;
};

// FNV-1a over the bytes of each frame's outcome.
struct Digest {
  uint64_t h = 1469598103934665603ull;
  void add(const void* p, size_t n) {
    for (size_t i = 0; i < n; ++i) h = (h ^ static_cast<const uint8_t*>(p)[i]) * 1099511628211ull;
  }
  template <class T>
  void add(const T& v) {
    add(&v, sizeof v);
  }
};

void print_stats(const std::string& name, const Stats& s) {
  const auto& c = s.cpu_ms;
  const auto& m = s.cpu_min_ms;
  std::printf(
      "%-24s frames %5d cpu p50/p90/p99/max %5.2f %5.2f %5.2f %5.2f ms, least of the passes "
      "%5.2f %5.2f %5.2f %5.2f ms | found %4d partial %4d | dW p5/p50/p95 %+6.3f %+6.3f %+6.3f | "
      "dH %+6.3f %+6.3f %+6.3f | dC p50/p95 %5.3f %5.3f m\n",
      name.c_str(), s.frames, quantile(c, 0.5), quantile(c, 0.9), quantile(c, 0.99),
      quantile(c, 1.0), quantile(m, 0.5), quantile(m, 0.9), quantile(m, 0.99), quantile(m, 1.0),
      s.found, s.partial, quantile(s.dw_m, 0.05), quantile(s.dw_m, 0.5), quantile(s.dw_m, 0.95),
      quantile(s.dh_m, 0.05), quantile(s.dh_m, 0.5), quantile(s.dh_m, 0.95), quantile(s.dc_m, 0.5),
      quantile(s.dc_m, 0.95));
}

void append(Stats* all, const Stats& s) {
  all->cpu_ms.insert(all->cpu_ms.end(), s.cpu_ms.begin(), s.cpu_ms.end());
  all->cpu_min_ms.insert(all->cpu_min_ms.end(), s.cpu_min_ms.begin(), s.cpu_min_ms.end());
  all->dw_m.insert(all->dw_m.end(), s.dw_m.begin(), s.dw_m.end());
  all->dh_m.insert(all->dh_m.end(), s.dh_m.begin(), s.dh_m.end());
  all->dc_m.insert(all->dc_m.end(), s.dc_m.begin(), s.dc_m.end());
  all->frames += s.frames, all->found += s.found, all->partial += s.partial;
}

}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{"alight_vision_cpu_bench: the vision's CPU time per frame and its accuracy"};
  std::string families = "ingress_photo,ingress_solid_photo", seeds = "1";
  std::vector<std::string> scenario_files;
  std::string vehicle = std::string(alight::build::source_dir()) + "/config/vehicles/pelican.yaml";
  std::string csv_path, frames_path;
  int passes = 2;
  double standoff_m = 2.0, loop_s = 8.0, rate_hz = 60.0;
  app.add_option("--families", families, "scene families (comma separated; '' for none)");
  app.add_option("--seeds", seeds, "seeds of each family (comma separated)");
  app.add_option("--scenario", scenario_files, "scenario files (in addition)");
  app.add_option("--passes", passes, "times the rendered flight is processed")
      ->check(CLI::Range(1, 100));
  app.add_option("--standoff-m", standoff_m, "the figure-eight's distance from the wall")
      ->check(CLI::Range(0.8, 6.0));
  app.add_option("--loop-s", loop_s, "length of the rendered flight")->check(CLI::Range(0.5, 60.0));
  app.add_option("--rate-hz", rate_hz, "camera rate")->check(CLI::Range(1.0, 240.0));
  app.add_option("--vehicle", vehicle, "vehicle file");
  app.add_option("--csv", csv_path, "one row per processed frame");
  app.add_option("--frames", frames_path, "every frame's whole result, exact, no timing");
  CLI11_PARSE(app, argc, argv);
  cv::setNumThreads(1);  // as alight-vision
  if (!retain_freed_memory()) std::fprintf(stderr, "glibc refused the heap settings\n");

  namespace fs = std::filesystem;
  std::vector<Scene> scenes;
  std::string dir_template = (fs::temp_directory_path() / "alight-cpu-bench-XXXXXX").string();
  if (!mkdtemp(dir_template.data())) {
    std::fprintf(stderr, "alight_vision_cpu_bench: cannot create a temporary folder\n");
    return 2;
  }
  const fs::path dir = dir_template;
  for (const auto& fam : split(families))
    for (const auto& s : split(seeds)) {
      const std::string cmd = "'" + std::string(alight::build::source_dir()) +
                              "/scripts/scenes' '" + fam + "' --seed " + s + " --out '" +
                              dir.string() + "' > /dev/null";
      if (std::system(cmd.c_str()) != 0) {
        std::fprintf(stderr, "alight_vision_cpu_bench: scripts/scenes failed for '%s'\n",
                     fam.c_str());
        return 2;
      }
      scenes.push_back({fam + "-" + s, (dir / (fam + "-" + s + ".yaml")).string(), std::stoull(s)});
    }
  for (const auto& f : scenario_files) scenes.push_back({fs::path(f).stem().string(), f, 1});

  std::ofstream csv;
  if (!csv_path.empty()) {
    csv.open(csv_path);
    csv << "scene,pass,frame,cpu_ms,reason,width_err_m,height_err_m,centre_err_m\n";
  }
  std::ofstream frames_out;
  if (!frames_path.empty()) frames_out.open(frames_path);
  Stats all;
  Digest all_digest;
  const auto params = vision::load_node_params(vehicle);
  for (const auto& sc : scenes) {
    sim::Scenario scenario = sim::load_scenario(sc.file);
    scenario.camera.rate_hz = rate_hz;
    const bench::Recorded rec =
        bench::record_one_period(scenario, vehicle, sc.seed, loop_s, rate_hz, standoff_m);
    // The camera as rendered: the vision undistorts with the scenario's lens, as the node does.
    auto rig = sim::load_camera_rig(vehicle, scenario.camera.mount);
    rig.model = sim::with_lens(rig.model, scenario.camera.effects);
    const vision::Mission mission =
        scenario.wall ? vision::Mission::kIngress : vision::Mission::kLanding;
    vision::Pipeline pipeline(mission, params.pipeline, rig.model, rig.mount);
    PoseBuffer poses(params.poses);
    Stats st;
    Digest digest;
    constexpr int64_t kT0 = 1'700'000'000'000'000;
    size_t next_pose = 0;
    int pass_of_pose = 0;
    for (int pass = 0; pass < passes; ++pass) {
      for (size_t i = 0; i < rec.frames.size(); ++i) {
        const int64_t t = kT0 + pass * rec.period_us + rec.frames[i].first;
        // Every pose up to 50 ms after the exposure (motion capture runs ahead of the camera).
        for (;;) {
          if (next_pose == rec.poses.size()) next_pose = 0, ++pass_of_pose;
          const int64_t tp = kT0 + pass_of_pose * rec.period_us + rec.poses[next_pose].first;
          if (tp > t + 50'000) break;
          PoseSample p = rec.poses[next_pose].second;
          p.utime = tp;
          poses.add(p);
          ++next_pose;
        }
        const auto pose = poses.at(t);
        const double t0 = thread_cpu_ms();
        const vision::FrameResult r = pipeline.process(
            rec.frames[i].second, t, pose, scenario.camera.exposure_s, rec.line_delay_s);
        const double cpu = thread_cpu_ms() - t0;
        st.cpu_ms.push_back(cpu);
        if (pass == 0)
          st.cpu_min_ms.push_back(cpu);
        else
          st.cpu_min_ms[i] = std::min(st.cpu_min_ms[i], cpu);
        ++st.frames;
        if (frames_out.is_open()) frames_out << sc.name << ' ' << vision::frame_line(r);
        digest.add(static_cast<int>(r.reason));
        digest.add(r.n_features), digest.add(r.n_matches);
        double dw = NAN, dh = NAN, dc = NAN;
        if (r.found() || vision::located_only(r.reason)) {
          for (int k = 0; k < 3; ++k) digest.add(r.target.p_W[k]);
          digest.add(r.target.size_m[0]), digest.add(r.target.size_m[1]);
        }
        if (r.found()) {
          ++st.found;
          if (rec.opening) {
            dw = r.target.size_m[0] - rec.opening->size_m.x();
            dh = r.target.size_m[1] - rec.opening->size_m.y();
            dc = (r.target.p_W - rec.opening->center_W).norm();
            st.dw_m.push_back(dw), st.dh_m.push_back(dh), st.dc_m.push_back(dc);
          }
        } else if (vision::located_only(r.reason)) {
          ++st.partial;
        }
        if (csv.is_open())
          csv << sc.name << ',' << pass << ',' << i << ',' << cpu << ','
              << vision::to_string(r.reason) << ',' << dw << ',' << dh << ',' << dc << '\n';
      }
    }
    print_stats(sc.name, st);
    std::printf("%-26s digest %016llx\n", "", static_cast<unsigned long long>(digest.h));
    std::fflush(stdout);
    append(&all, st);
    all_digest.add(digest.h);
  }
  print_stats("all", all);
  std::printf("%-26s digest %016llx\n", "", static_cast<unsigned long long>(all_digest.h));
  std::error_code ec;
  fs::remove_all(dir, ec);
  return 0;
} catch (const alight::ParamError& e) {
  // A bad scenario or vehicle file: the message names the file, the key and the value.
  std::fprintf(stderr, "alight_vision_cpu_bench: configuration error: %s\n", e.what());
  return 2;
}
