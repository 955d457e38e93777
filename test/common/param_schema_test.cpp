// ParamSchema (issue 18): one declaration per parameter gives reading, validation with the full
// dotted key and a message built from the constraint, and a dump that reads back.
#include "common/param_schema.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <sstream>

#include "test/common/expect_param_error.hpp"

namespace alight {
namespace {

using test::expect_param_error;

struct Inner {
  int max_size = 45;
  uint64_t seed = 7;
  static const ParamSchema<Inner>& schema() {
    static const ParamSchema<Inner> s = [] {
      ParamSchema<Inner> s;
      s.add("max_size", &Inner::max_size, Range::closed(4, 64), "px", "largest filter size");
      s.add("seed", &Inner::seed, Range::any(), "", "random seed");
      return s;
    }();
    return s;
  }
};

struct Shared {
  double baseline_m = 0.1;
  static const ParamSchema<Shared>& schema() {
    static const ParamSchema<Shared> s = [] {
      ParamSchema<Shared> s;
      s.add("baseline_m", &Shared::baseline_m, Range::gt(0), "m", "shortest baseline");
      return s;
    }();
    return s;
  }
};

struct Box {
  Eigen::Vector2d size_m{0.5, 0.4};
  static const ParamSchema<Box>& schema() {
    static const ParamSchema<Box> s = [] {
      ParamSchema<Box> s;
      s.add("size_m", &Box::size_m, Range::gt(0), "m", "width and depth").required();
      return s;
    }();
    return s;
  }
};

struct Outer {
  double timeout_s = 0.5;
  double lost_s = 1.0;
  int count = 3;
  bool robust = true;
  std::string format = "GREY";
  Eigen::Vector3d offset_m{0, 0, 0.1};
  std::array<double, 2> window{1.0, 2.0};
  Inner inner;
  Shared shared;
  std::optional<Box> box;
  static const ParamSchema<Outer>& schema() {
    static const ParamSchema<Outer> s = [] {
      ParamSchema<Outer> s;
      s.add("timeout_s", &Outer::timeout_s, Range::open_closed(0, 2), "s", "wait at most");
      s.add("lost_s", &Outer::lost_s, Range::le(5), "s", "give up after")
          .check([](const Outer& o) { return o.lost_s > o.timeout_s; }, "must exceed timeout_s");
      s.add("count", &Outer::count, Range::ge(1), "", "how many");
      s.add("robust", &Outer::robust, Range::any(), "", "Cauchy weights");
      s.add("format", &Outer::format, Range::any(), "", "pixel format")
          .one_of({"GREY", "YUYV", "MJPEG"});
      s.add("offset_m", &Outer::offset_m, Range::any(), "m", "camera offset");
      s.add("window", &Outer::window, Range::gt(0), "s", "first and last");
      s.section("inner", &Outer::inner, Inner::schema(), "the detector");
      s.merge(&Outer::shared, Shared::schema());
      s.optional_section("box", &Outer::box, Box::schema(), "an obstacle");
      s.check(
          "count", [](const Outer& o) { return o.count <= o.inner.max_size; },
          "must not exceed inner.max_size");
      return s;
    }();
    return s;
  }
};

Outer load_outer(const std::string& yaml) {
  const auto root = ParamNode::from_string(yaml, "v.yaml");
  Outer o;
  Outer::schema().read(root.child("top"), o);
  return o;
}

TEST(ParamSchemaTest, AbsentKeysKeepTheInitialisersAndPresentOnesAreRead) {
  const Outer o = load_outer(
      "top:\n  timeout_s: 0.25\n  format: MJPEG\n  offset_m: [1, 2, 3]\n  baseline_m: 0.3\n"
      "  inner: {seed: 42}\n");
  EXPECT_EQ(o.timeout_s, 0.25);
  EXPECT_EQ(o.lost_s, 1.0);
  EXPECT_EQ(o.format, "MJPEG");
  EXPECT_EQ(o.offset_m, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(o.shared.baseline_m, 0.3);
  EXPECT_EQ(o.inner.seed, 42u);
  EXPECT_EQ(o.inner.max_size, 45);
  EXPECT_FALSE(o.box.has_value());
}

TEST(ParamSchemaTest, ErrorsNameTheFullKeyTheValueAsWrittenAndTheConstraint) {
  auto e = expect_param_error([] { load_outer("top:\n  timeout_s: 3\n"); });
  EXPECT_EQ(std::string(e.what()), "v.yaml: top.timeout_s = 3: must be in (0, 2] s");
  e = expect_param_error([] { load_outer("top:\n  inner:\n    max_size: 80\n"); });
  EXPECT_EQ(std::string(e.what()), "v.yaml: top.inner.max_size = 80: must be in [4, 64] px");
  e = expect_param_error([] { load_outer("top:\n  count: 0\n"); });
  EXPECT_EQ(std::string(e.what()), "v.yaml: top.count = 0: must be >= 1");
  e = expect_param_error([] { load_outer("top:\n  format: RGB3\n"); });
  EXPECT_EQ(std::string(e.what()), "v.yaml: top.format = RGB3: must be GREY, YUYV or MJPEG");
  e = expect_param_error([] { load_outer("top:\n  window: [1, -2]\n"); });
  EXPECT_EQ(std::string(e.what()), "v.yaml: top.window = [1, -2]: must be > 0 s");
  e = expect_param_error([] { load_outer("top:\n  baseline_m: 0\n"); });
  EXPECT_EQ(e.key(), "top.baseline_m");  // merged: at the level of the file where it is written
}

TEST(ParamSchemaTest, CrossFieldChecksNameTheirKey) {
  auto e = expect_param_error([] { load_outer("top:\n  timeout_s: 2\n  lost_s: 1.5\n"); });
  EXPECT_EQ(std::string(e.what()), "v.yaml: top.lost_s = 1.5: must exceed timeout_s");
  e = expect_param_error([] { load_outer("top:\n  count: 50\n"); });
  EXPECT_EQ(std::string(e.what()), "v.yaml: top.count = 50: must not exceed inner.max_size");
}

TEST(ParamSchemaTest, NonFiniteWrongTypeUnknownAndMissingRequiredKeysAreRefused) {
  auto e = expect_param_error([] { load_outer("top:\n  timeout_s: .inf\n"); });
  EXPECT_EQ(std::string(e.what()), "v.yaml: top.timeout_s = .inf: expected a finite number");
  e = expect_param_error([] { load_outer("top:\n  inner:\n    seed: -1\n"); });
  EXPECT_EQ(std::string(e.what()), "v.yaml: top.inner.seed = -1: expected a non-negative integer");
  e = expect_param_error([] { load_outer("top:\n  inner:\n    max_sise: 10\n"); });
  EXPECT_EQ(e.key(), "top.inner.max_sise");
  EXPECT_NE(e.problem().find("unknown key"), std::string::npos);
  e = expect_param_error([] { load_outer("top:\n  box: {}\n"); });
  EXPECT_EQ(e.key(), "top.box.size_m");
  e = expect_param_error([] { load_outer("top:\n  box:\n    other: 1\n"); });
  EXPECT_EQ(std::string(e.what()), "v.yaml: top.box.size_m = <missing>: required key is missing");
}

TEST(ParamSchemaTest, StructsBuiltInCodeAreValidatedWithTheSameMessages) {
  Outer o;
  o.inner.max_size = 2;
  auto e = expect_param_error([&] { Outer::schema().validate(o); });
  EXPECT_EQ(std::string(e.what()), "inner.max_size = 2: must be in [4, 64] px");
  o = Outer{};
  o.timeout_s = std::nan("");
  e = expect_param_error([&] { Outer::schema().validate(o); });
  EXPECT_EQ(std::string(e.what()), "timeout_s = .nan: must be finite");
  o = Outer{};
  o.box = Box{Eigen::Vector2d(0.5, -1)};
  e = expect_param_error([&] { Outer::schema().validate(o); });
  EXPECT_EQ(e.key(), "box.size_m");
}

TEST(ParamSchemaTest, ListsEveryParameterWithItsFullKeyUnitAndRule) {
  const auto params = Outer::schema().params(Outer{});
  std::vector<std::string> keys;
  for (const auto& p : params) keys.push_back(p.key);
  EXPECT_EQ(keys, (std::vector<std::string>{"timeout_s", "lost_s", "count", "robust", "format",
                                            "offset_m", "window", "inner.max_size", "inner.seed",
                                            "baseline_m", "box.size_m"}));
  EXPECT_EQ(params[0].unit, "s");
  EXPECT_EQ(params[0].rule, "in (0, 2] s");
  EXPECT_EQ(params[0].value, "0.5");
  EXPECT_EQ(params[4].rule, "one of GREY, YUYV, MJPEG");
  EXPECT_EQ(params[4].value, "\"GREY\"");
  EXPECT_EQ(params[5].value, "[0, 0, 0.1]");
  EXPECT_TRUE(params[10].required);
}

// Property: the dump of any valid struct reads back to the same struct, absent optional
// sections staying absent.
TEST(ParamSchemaTest, TheDumpReadsBackToTheSameValues) {
  for (const bool with_box : {false, true}) {
    Outer o;
    o.timeout_s = 0.1 + 1e-12;  // needs every digit to round-trip
    o.format = "YUYV";
    o.offset_m = Eigen::Vector3d(-1.0 / 3, 2e-9, 1e6);
    o.inner.seed = 123456789012345ull;
    o.robust = false;
    if (with_box) o.box = Box{Eigen::Vector2d(0.33, 0.26)};
    std::ostringstream text;
    text << "top:\n";
    Outer::schema().dump(text, o, 2);
    const Outer r = load_outer(text.str());
    EXPECT_EQ(r.timeout_s, o.timeout_s) << text.str();
    EXPECT_EQ(r.format, o.format);
    EXPECT_EQ(r.offset_m, o.offset_m);
    EXPECT_EQ(r.inner.seed, o.inner.seed);
    EXPECT_EQ(r.robust, o.robust);
    EXPECT_EQ(r.box.has_value(), with_box) << text.str();
    if (with_box) {
      EXPECT_EQ(r.box->size_m, o.box->size_m);
    }
    EXPECT_NE(text.str().find("# wait at most; in (0, 2] s\n  timeout_s: "), std::string::npos)
        << text.str();
  }
}

TEST(ParamSchemaTest, RangeTextsAndBoundaries) {
  EXPECT_TRUE(Range::open_closed(0, 2).contains(2));
  EXPECT_FALSE(Range::open_closed(0, 2).contains(0));
  EXPECT_TRUE(Range::closed_open(0, 2).contains(0));
  EXPECT_FALSE(Range::closed_open(0, 2).contains(2));
  EXPECT_FALSE(Range::any().contains(std::nan("")));
  EXPECT_FALSE(Range::le(5).contains(std::nan("")));
  EXPECT_EQ(Range::lt(1e6).text("Hz"), "< 1e+06 Hz");
  EXPECT_EQ(Range::closed(0.001, 1).text(""), "in [0.001, 1]");
  EXPECT_EQ(Range::any().text("s"), "");
}

// A struct that is flat in code and nested in the file (group), with a presence flag; a message
// that depends on the value (check_with); a path resolved against the file's folder.
struct Wall {
  double width_m = 4.0;
  bool has_opening = true;
  double opening_width_m = 0.6;
  std::string texture = "";
  std::string device = "/dev/video0";
  static const ParamSchema<Wall>& schema() {
    static const ParamSchema<Wall> s = [] {
      ParamSchema<Wall> s;
      s.add("width_m", &Wall::width_m, Range::gt(0.2), "m", "along y");
      s.group(
          "opening", "a hole in it",
          [](ParamSchema<Wall>& g) {
            g.add("width_m", &Wall::opening_width_m, Range::gt(0.05), "m", "of the hole");
          },
          &Wall::has_opening);
      s.add("texture", &Wall::texture, Range::any(), "", "an image").path();
      s.add("device", &Wall::device, Range::any(), "", "a device").check_with([](const Wall& w) {
        return w.device.rfind("/dev/", 0) == 0 ? std::string()
                                               : "must start with /dev/, not " + w.device;
      });
      s.check(
          "opening.width_m",
          [](const Wall& w) { return !w.has_opening || w.opening_width_m < w.width_m; },
          "must be narrower than the wall");
      return s;
    }();
    return s;
  }
};

Wall load_wall(const std::string& yaml) {
  Wall w;
  Wall::schema().read(ParamNode::from_string(yaml, "dir/w.yaml").child("wall"), w);
  return w;
}

TEST(ParamSchemaTest, AGroupNestsFieldsOfTheSameStructAndItsFlagSaysWhetherItIsThere) {
  Wall w = load_wall("wall:\n  opening: {width_m: 0.8}\n");
  EXPECT_TRUE(w.has_opening);
  EXPECT_EQ(w.opening_width_m, 0.8);
  w = load_wall("wall: {width_m: 0.3}\n");
  EXPECT_FALSE(w.has_opening);  // and the opening, wider than the wall, is not checked
  auto e = expect_param_error([] { load_wall("wall:\n  opening: {width_m: 0.01}\n"); });
  EXPECT_EQ(std::string(e.what()), "dir/w.yaml: wall.opening.width_m = 0.01: must be > 0.05 m");
  e = expect_param_error([] { load_wall("wall:\n  width_m: 0.5\n  opening: {width_m: 0.6}\n"); });
  EXPECT_EQ(std::string(e.what()),
            "dir/w.yaml: wall.opening.width_m = 0.6: must be narrower than the wall");
  e = expect_param_error([] { load_wall("wall:\n  opening: {widht_m: 0.6}\n"); });
  EXPECT_EQ(e.key(), "wall.opening.widht_m");
  // Dumped as comments when absent, so the dump reads back without it.
  w = load_wall("wall: {width_m: 0.3}\n");
  std::ostringstream text;
  text << "wall:\n";
  Wall::schema().dump(text, w, 2);
  EXPECT_NE(text.str().find("  # opening:\n"), std::string::npos) << text.str();
  EXPECT_FALSE(load_wall(text.str()).has_opening);
  const auto keys = Wall::schema().params(w);
  EXPECT_EQ(keys[1].key, "opening.width_m");
}

TEST(ParamSchemaTest, PathsAreResolvedAgainstTheFilesFolderAndMessagesMayDependOnTheValue) {
  EXPECT_EQ(load_wall("wall: {texture: img/a.png}\n").texture, "dir/img/a.png");
  EXPECT_EQ(load_wall("wall: {texture: /abs/a.png}\n").texture, "/abs/a.png");
  EXPECT_EQ(load_wall("wall: {}\n").texture, "");  // an empty default stays empty
  const auto e = expect_param_error([] { load_wall("wall: {device: video0}\n"); });
  EXPECT_EQ(std::string(e.what()),
            "dir/w.yaml: wall.device = video0: must start with /dev/, not video0");
}

// A value out of its own range is reported at its key, even when the check of a key declared
// before it involves it (ranges first, then checks, then relations).
struct Span {
  double low = 1;
  double high = 2;
  static const ParamSchema<Span>& schema() {
    static const ParamSchema<Span> s = [] {
      ParamSchema<Span> s;
      s.add("low", &Span::low, Range::any(), "m", "start")
          .check([](const Span& p) { return p.low < p.high; }, "must be below high");
      s.add("high", &Span::high, Range::le(10), "m", "end");
      return s;
    }();
    return s;
  }
};

TEST(ParamSchemaTest, AValueOutOfRangeIsReportedAtItsOwnKeyBeforeAnyCheckThatInvolvesIt) {
  Span p{30, 20};
  auto e = expect_param_error([&] { Span::schema().validate(p); });
  EXPECT_EQ(std::string(e.what()), "high = 20: must be <= 10 m");
  p = Span{9, 8};
  e = expect_param_error([&] { Span::schema().validate(p); });
  EXPECT_EQ(std::string(e.what()), "low = 9: must be below high");
}

// Error values show the value as it was understood (1e9 as 1e+09), as the dump would write it.
TEST(ParamSchemaTest, ErrorsShowTheValueAsTheDumpWritesIt) {
  auto e = expect_param_error([] { load_outer("top:\n  timeout_s: 1e9\n"); });
  EXPECT_EQ(e.value(), "1e+09");
  e = expect_param_error([] { load_outer("top:\n  format: \"RGB 3\"\n"); });
  EXPECT_EQ(e.value(), "RGB 3");
}

TEST(ParamSchemaTest, ParamInfoCarriesTheRangeAndWhetherTheParameterIsAnInteger) {
  const auto params = Outer::schema().params(Outer{});
  EXPECT_EQ(*params[0].range.lo(), 0);
  EXPECT_FALSE(params[0].range.lo_closed());
  EXPECT_EQ(*params[0].range.hi(), 2);
  EXPECT_TRUE(params[0].range.hi_closed());
  EXPECT_FALSE(params[0].integer);
  EXPECT_TRUE(params[2].integer);                  // count
  EXPECT_FALSE(params[3].integer);                 // robust: a bool is no integer
  EXPECT_FALSE(params[1].range.lo().has_value());  // lost_s: <= 5
}

}  // namespace
}  // namespace alight
