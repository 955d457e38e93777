#include "common/params.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <future>
#include <string>
#include <vector>

#include "common/build_paths.hpp"
#include "common/camera_mount.hpp"
#include "common/pose_buffer.hpp"
#include "test/common/expect_param_error.hpp"

namespace alight {
namespace {

using test::expect_param_error;

struct Refinement {
  int n_min = 10;
  double eps_horz_m = 0.01;
  void validate() const {
    param_check(n_min >= 1, "n_min", n_min, "must be >= 1");
    param_check(eps_horz_m > 0, "eps_horz_m", eps_horz_m, "must be > 0");
  }
};

Refinement load(const std::string& yaml) {
  const auto root = ParamNode::from_string(yaml, "config/vehicles/test.yaml");
  const auto sec = root.child("autonomy").child("refinement");
  Refinement r;
  sec.read("n_min", r.n_min);
  sec.read("eps_horz_m", r.eps_horz_m);
  sec.finish();
  sec.validate(r);
  return r;
}

TEST(ParamsTest, AbsentKeysKeepTheirDefaults) {
  const auto r = load("autonomy:\n  refinement:\n    n_min: 12\n");
  EXPECT_EQ(r.n_min, 12);
  EXPECT_DOUBLE_EQ(r.eps_horz_m, 0.01);
}

TEST(ParamsTest, ValidationErrorNamesFileKeyAndValue) {
  const auto e = expect_param_error([] { load("autonomy:\n  refinement:\n    n_min: -3\n"); });
  EXPECT_EQ(e.file(), "config/vehicles/test.yaml");
  EXPECT_EQ(e.key(), "autonomy.refinement.n_min");
  EXPECT_EQ(e.value(), "-3");
  EXPECT_EQ(std::string(e.what()),
            "config/vehicles/test.yaml: autonomy.refinement.n_min = -3: must be >= 1");
}

TEST(ParamsTest, WrongTypeNamesTheExpectedType) {
  const auto e = expect_param_error([] { load("autonomy:\n  refinement:\n    n_min: ten\n"); });
  EXPECT_EQ(e.key(), "autonomy.refinement.n_min");
  EXPECT_EQ(e.value(), "ten");
  EXPECT_NE(std::string(e.what()).find("integer"), std::string::npos);
}

TEST(ParamsTest, MisspeltKeyIsRejected) {
  const auto e = expect_param_error([] { load("autonomy:\n  refinement:\n    n_mim: 4\n"); });
  EXPECT_EQ(e.key(), "autonomy.refinement.n_mim");
  EXPECT_NE(e.problem().find("unknown key"), std::string::npos);
}

TEST(ParamsTest, MissingSectionIsNamed) {
  const auto e = expect_param_error([] { load("autonomy: {}\n"); });
  EXPECT_EQ(e.key(), "autonomy.refinement");
  EXPECT_EQ(e.value(), "<missing>");
}

TEST(ParamsTest, SectionThatIsNotAMappingIsRejected) {
  const auto e = expect_param_error([] { load("autonomy:\n  refinement: 3\n"); });
  EXPECT_EQ(e.key(), "autonomy.refinement");
  EXPECT_EQ(e.value(), "3");
}

TEST(ParamsTest, InvalidYamlNamesTheLine) {
  const auto e = expect_param_error([] { ParamNode::from_string("a: 1\nb: [1, 2\n", "f.yaml"); });
  EXPECT_EQ(e.file(), "f.yaml");
  EXPECT_NE(std::string(e.what()).find("line"), std::string::npos);
}

TEST(ParamsTest, MissingFileIsNamed) {
  const auto e = expect_param_error([] { ParamNode::load_file("/nonexistent/alight.yaml"); });
  EXPECT_EQ(e.file(), "/nonexistent/alight.yaml");
  EXPECT_NE(e.problem().find("cannot open"), std::string::npos);
}

TEST(ParamsTest, VectorOfWrongLengthIsRejected) {
  const auto root = ParamNode::from_string("t: [1, 2]\n", "v.yaml");
  Vector3d t;
  const auto e = expect_param_error([&] { root.require("t", t); });
  EXPECT_EQ(e.key(), "t");
  EXPECT_EQ(e.value(), "[1, 2]");
}

TEST(ParamsTest, RequiredKeyMissingIsNamed) {
  const auto root = ParamNode::from_string("a: 1\n", "r.yaml");
  double b = 0;
  const auto e = expect_param_error([&] { root.require("b", b); });
  EXPECT_EQ(std::string(e.what()), "r.yaml: b = <missing>: required key is missing");
}

TEST(ParamsTest, ListOfMappingsNamesTheIndex) {
  const auto root = ParamNode::from_string("procs:\n  - {name: a}\n  - 7\n", "l.yaml");
  const auto e = expect_param_error([&] { root.child_list("procs"); });
  EXPECT_EQ(e.key(), "procs[1]");
}

TEST(ParamsTest, PoseBufferParamsValidate) {
  PoseBufferParams p;
  p.max_gap_s = -1;
  const auto e = expect_param_error([&] { p.validate(); });
  EXPECT_EQ(e.key(), "max_gap_s");
  EXPECT_EQ(e.value(), "-1");
}

TEST(ParamsTest, CameraMountResolvesRelativeToTheVehicleFile) {
  const std::string vehicle =
      std::string(alight::build::source_dir()) + "/config/vehicles/pelican.yaml";
  const auto root = ParamNode::load_file(vehicle);
  const auto down = load_camera_mount(root, "downward");
  EXPECT_TRUE(std::filesystem::exists(down.camera_info_path)) << down.camera_info_path;
  EXPECT_TRUE(is_rotation(down.R_BC));
  EXPECT_TRUE(down.R_BC.isApprox(R_BC_downward()));
  const auto fwd = load_camera_mount(root, "forward");
  EXPECT_TRUE(fwd.R_BC.isApprox(R_BC_forward()));
}

TEST(ParamsTest, CameraMountRejectsUnknownMount) {
  const auto root = ParamNode::from_string(
      "cameras:\n  downward:\n    camera_info: x.yaml\n    mount: sideways\n    t_B_C_m: [0,0,0]\n",
      "veh.yaml");
  const auto e = expect_param_error([&] { load_camera_mount(root, "downward"); });
  EXPECT_EQ(e.key(), "cameras.downward.mount");
  EXPECT_EQ(e.value(), "sideways");
}

// Regression (issue 14): `.inf` loaded for pose_lost_s / failsafe_disarm_after_s /
// setpoint_lost_s and turned the failsafes off; NaN passed every `x > 0` check as false but
// `!(x <= 0)` style checks as true.
TEST(ParamsTest, NonFiniteNumbersAreRefusedWithTheFullKey) {
  for (const char* v : {".inf", "-.inf", ".nan", ".NaN", "1e999"}) {
    const auto e = expect_param_error(
        [&] { load(std::string("autonomy:\n  refinement:\n    eps_horz_m: ") + v + "\n"); });
    EXPECT_EQ(e.key(), "autonomy.refinement.eps_horz_m") << v;
    EXPECT_EQ(e.value(), v);
    EXPECT_EQ(e.file(), "config/vehicles/test.yaml");
    EXPECT_NE(std::string(e.what()).find("finite"), std::string::npos) << e.what();
  }
}

TEST(ParamsTest, NonFiniteNumbersInAListAreRefused) {
  const auto root = ParamNode::from_string("p: [1, .nan, 3]\n", "f.yaml");
  Eigen::Vector3d v;
  const auto e = expect_param_error([&] { root.read("p", v); });
  EXPECT_EQ(e.key(), "p");
}

// Regression (issue 14): a duplicate YAML key was taken silently (yaml-cpp keeps both entries
// and lookups see the first, so the later line, usually the edit, did nothing).
TEST(ParamsTest, DuplicateKeyIsRefusedWithItsFullKeyAndLine) {
  const auto e = expect_param_error(
      [] { load("autonomy:\n  refinement:\n    n_min: 3\n    eps_horz_m: 0.1\n    n_min: 5\n"); });
  EXPECT_EQ(e.key(), "autonomy.refinement.n_min");
  EXPECT_EQ(e.value(), "5");
  EXPECT_EQ(e.file(), "config/vehicles/test.yaml");
  EXPECT_NE(std::string(e.what()).find("line 5"), std::string::npos) << e.what();
}

TEST(ParamsTest, DuplicateKeyInsideAListIsRefused) {
  const auto e = expect_param_error(
      [] { ParamNode::from_string("procs:\n  - name: a\n    name: b\n", "launch.yaml"); });
  EXPECT_EQ(e.key(), "procs[0].name");
}

TEST(ParamsTest, SameKeyInDifferentMappingsIsFine) {
  EXPECT_NO_THROW(ParamNode::from_string("a:\n  x: 1\nb:\n  x: 2\n", "f.yaml"));
}

// Regression (issue 14, found by fuzzing): a key that is a list or a mapping threw yaml-cpp's
// BadConversion from finish(), and every node exited 1 naming no key.
TEST(ParamsTest, NonScalarKeyIsAParamErrorNamingWhere) {
  const auto root = ParamNode::from_string("ground_station:\n  {[a]: 1}\n", "station.yaml");
  const auto sec = root.child("ground_station");
  const auto e = expect_param_error([&] { sec.finish(); });
  EXPECT_EQ(e.file(), "station.yaml");
  EXPECT_EQ(e.key(), "ground_station.<list as a key>");
}

// Files that must not hang or exhaust a node: each is refused with a ParamError naming it.
class ParamFileTest : public ::testing::Test {
 protected:
  std::filesystem::path dir = std::filesystem::temp_directory_path() /
                              ("alight_param_file_test_" + std::to_string(::getpid()));
  void SetUp() override { std::filesystem::create_directories(dir); }
  void TearDown() override { std::filesystem::remove_all(dir); }
  std::string path(const std::string& name) const { return (dir / name).string(); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path(name), std::ios::binary) << text;
    return path(name);
  }
  std::string fifo(const std::string& name) const {
    const std::string p = path(name);
    EXPECT_EQ(::mkfifo(p.c_str(), 0600), 0) << std::strerror(errno);
    return p;
  }
  // A file of `bytes` that takes no disk: ftruncate leaves a hole.
  std::string sparse(const std::string& name, off_t bytes) const {
    const std::string p = path(name);
    const int fd = ::open(p.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    EXPECT_GE(fd, 0);
    EXPECT_EQ(::ftruncate(fd, bytes), 0);
    ::close(fd);
    return p;
  }
};

ParamError refused_file(const std::string& path) {
  return expect_param_error([&] { ParamNode::load_file(path); });
}

TEST_F(ParamFileTest, FifoIsRefusedWithoutBlocking) {
  const std::string p = fifo("vehicle.yaml");
  auto refused = std::async(std::launch::async, [&] { return refused_file(p); });
  // Not a measure of speed: a loader stuck in open() or read() of the FIFO (it has no writer)
  // is released by a writer that closes at once, so a regression fails instead of hanging.
  if (refused.wait_for(std::chrono::seconds(10)) != std::future_status::ready) {
    const int w = ::open(p.c_str(), O_WRONLY | O_NONBLOCK);
    if (w >= 0) ::close(w);
    ADD_FAILURE() << "load_file blocked on a FIFO";
  }
  const ParamError e = refused.get();
  EXPECT_EQ(e.file(), p);
  EXPECT_NE(e.problem().find("not a regular file (a FIFO)"), std::string::npos) << e.what();
}

TEST_F(ParamFileTest, SymlinkToAFifoIsRefusedAndToAFileFollowed) {
  const std::string target = fifo("fifo");
  std::filesystem::create_symlink(target, path("link.yaml"));
  EXPECT_NE(refused_file(path("link.yaml")).problem().find("FIFO"), std::string::npos);
  std::filesystem::create_symlink(write("real.yaml", "a: 1\n"), path("good.yaml"));
  int a = 0;
  ParamNode::load_file(path("good.yaml")).require("a", a);
  EXPECT_EQ(a, 1);
}

TEST_F(ParamFileTest, DevicesAndDirectoriesAreRefused) {
  const ParamError zero = refused_file("/dev/zero");
  EXPECT_EQ(zero.file(), "/dev/zero");
  EXPECT_NE(zero.problem().find("character device"), std::string::npos) << zero.what();
  EXPECT_NE(refused_file("/dev/null").problem().find("character device"), std::string::npos);
  EXPECT_NE(refused_file(dir.string()).problem().find("directory"), std::string::npos);
}

TEST_F(ParamFileTest, LargeFilesAreRefusedBeforeReading) {
  const std::string huge = sparse("huge.yaml", off_t{300} << 20);
  const ParamError e = refused_file(huge);
  EXPECT_EQ(e.file(), huge);
  EXPECT_EQ(e.problem(), "file too large: 314572800 bytes, at most 1 MiB");
  EXPECT_NE(
      refused_file(sparse("over.yaml", ParamNode::kMaxFileBytes + 1)).problem().find("too large"),
      std::string::npos);
}

TEST_F(ParamFileTest, AFileOfExactlyTheLimitLoads) {
  std::string text = "a: 1\n#";
  text += std::string(ParamNode::kMaxFileBytes - text.size() - 1, 'x') + "\n";
  ASSERT_EQ(text.size(), ParamNode::kMaxFileBytes);
  int a = 0;
  ParamNode::load_file(write("limit.yaml", text)).require("a", a);
  EXPECT_EQ(a, 1);
  const auto e = expect_param_error([&] { ParamNode::from_string(text + "\n", "mem.yaml"); });
  EXPECT_EQ(e.file(), "mem.yaml");
  EXPECT_NE(e.problem().find("too large"), std::string::npos);
}

// "Billion laughs": 9 levels of 9 aliases, under 1 kB of text, a billion values when walked.
TEST_F(ParamFileTest, AliasBombIsRefusedAtItsFirstAnchor) {
  std::string text = "l0: &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n";
  for (int i = 1; i <= 9; ++i) {
    const std::string prev = "*l" + std::to_string(i - 1);
    text += "l" + std::to_string(i) + ": &l" + std::to_string(i) + " [";
    for (int j = 0; j < 9; ++j) text += (j ? ", " : "") + prev;
    text += "]\n";
  }
  ASSERT_LT(text.size(), 1000u);
  const std::string p = write("bomb.yaml", text);
  const ParamError e = refused_file(p);
  EXPECT_EQ(e.file(), p);
  EXPECT_EQ(e.problem(),
            "line 1: YAML anchors (&name) are not accepted in parameter files: write the values "
            "out");
}

TEST_F(ParamFileTest, AnchorsAliasesAndMergeKeysAreRefused) {
  EXPECT_NE(expect_param_error([] { ParamNode::from_string("a: &x 1\nb: 2\n", "f.yaml"); })
                .problem()
                .find("line 1: YAML anchors"),
            std::string::npos);
  // An alias of an anchor nobody defined is a parse error in yaml-cpp: refused all the same.
  const auto alias = expect_param_error([] { ParamNode::from_string("a: 1\nb: *x\n", "f.yaml"); });
  EXPECT_EQ(alias.file(), "f.yaml");
  EXPECT_NE(alias.problem().find("line 2"), std::string::npos) << alias.what();
  const auto merge = expect_param_error(
      [] { ParamNode::from_string("base: &b {x: 1}\nderived:\n  <<: *b\n", "m.yaml"); });
  EXPECT_EQ(merge.file(), "m.yaml");
}

TEST_F(ParamFileTest, NestingIsBounded) {
  const auto nested = [](int levels) {
    return "a: " + std::string(levels, '[') + std::string(levels, ']') + "\n";
  };
  // The top-level mapping is the first level.
  EXPECT_NO_THROW(ParamNode::from_string(nested(ParamNode::kMaxDepth - 1), "ok.yaml"));
  const std::string p = write("deep.yaml", nested(ParamNode::kMaxDepth));
  const ParamError e = refused_file(p);
  EXPECT_EQ(e.file(), p);
  EXPECT_EQ(e.problem(), "line 1: nested deeper than 32 levels");
  // Far deeper than any parser or tree walk would survive by recursion.
  EXPECT_NE(refused_file(write("abyss.yaml", nested(200'000))).problem().find("deeper"),
            std::string::npos);
  std::string block;
  for (int i = 0; i <= ParamNode::kMaxDepth; ++i)
    block += std::string(2 * i, ' ') + "k" + std::to_string(i) + ":\n";
  EXPECT_NE(expect_param_error([&] { ParamNode::from_string(block, "block.yaml"); })
                .problem()
                .find("deeper"),
            std::string::npos);
}

TEST_F(ParamFileTest, NodeCountIsBounded) {
  const auto list = [](size_t n) {
    std::string text = "a: [0";
    for (size_t i = 1; i < n; ++i) text += ",0";
    return text + "]\n";
  };
  // The mapping, its key and the list are three nodes.
  EXPECT_NO_THROW(ParamNode::from_string(list(ParamNode::kMaxNodes - 3), "ok.yaml"));
  const std::string p = write("many.yaml", list(ParamNode::kMaxNodes - 2));
  const ParamError e = refused_file(p);
  EXPECT_EQ(e.file(), p);
  EXPECT_EQ(e.problem(), "line 1: more than 100000 values");
}

#ifdef ALIGHT_HAVE_OUTER_LOOP
struct Exit {
  int code = -1;  ///< exit status, or -1 when it had to be killed
  std::string output;
};

// Runs a node with its output captured. The 10 s are a backstop for a node that hangs (it is
// then killed and the test fails), not a measure of speed.
Exit run_node(const std::vector<std::string>& args) {
  int out[2];
  if (::pipe(out) != 0) return {};
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::dup2(out[1], 1);
    ::dup2(out[1], 2);
    ::close(out[0]);
    ::close(out[1]);
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  ::close(out[1]);
  Exit result;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  bool killed = false;
  for (;;) {
    pollfd p{out[0], POLLIN, 0};
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      ::kill(pid, SIGKILL);
      killed = true;
      break;
    }
    if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) continue;
    char buf[4096];
    const ssize_t n = ::read(out[0], buf, sizeof buf);
    if (n <= 0) break;
    result.output.append(buf, static_cast<size_t>(n));
  }
  ::close(out[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  if (!killed && WIFEXITED(status)) result.code = WEXITSTATUS(status);
  return result;
}

TEST_F(ParamFileTest, ANodeGivenAFifoADeviceOrAHugeFileExitsTwoNamingIt) {
  for (const std::string& config :
       {fifo("fifo.yaml"), std::string("/dev/zero"), sparse("huge.yaml", off_t{300} << 20)}) {
    const Exit r = run_node({alight::build::program("alight-outer-loop"), "--config", config});
    EXPECT_EQ(r.code, 2) << config << ": " << r.output;
    EXPECT_NE(r.output.find("configuration error: " + config + ": "), std::string::npos)
        << r.output;
  }
}
#endif

}  // namespace
}  // namespace alight
