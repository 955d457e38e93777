#include "camera_driver/stored_source.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

namespace alight::camera {

namespace fs = std::filesystem;

std::optional<SourceSpec> parse_source(const std::string& text, std::string* error) {
  SourceSpec s;
  if (text == "camera") return s;
  if (text.rfind("file:", 0) == 0 && text.size() > 5) {
    s.kind = SourceSpec::Kind::kVideoFile;
    s.path = text.substr(5);
    return s;
  }
  if (text.rfind("folder:", 0) == 0 && text.size() > 7) {
    s.kind = SourceSpec::Kind::kFolder;
    s.path = text.substr(7);
    return s;
  }
  if (error) *error = "source '" + text + "': expected camera, file:PATH or folder:DIR";
  return std::nullopt;
}

cv::Mat to_encoding(const cv::Mat& image, OutputEncoding encoding) {
  cv::Mat out;
  const bool gray = image.channels() == 1;
  switch (encoding) {
    case OutputEncoding::kMono8:
      if (gray) return image;
      cv::cvtColor(image, out, image.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
      return out;
    case OutputEncoding::kRgb8:
      cv::cvtColor(image, out,
                   gray ? cv::COLOR_GRAY2RGB
                        : (image.channels() == 4 ? cv::COLOR_BGRA2RGB : cv::COLOR_BGR2RGB));
      return out;
    case OutputEncoding::kBgr8:
      if (image.channels() == 3) return image;
      cv::cvtColor(image, out, gray ? cv::COLOR_GRAY2BGR : cv::COLOR_BGRA2BGR);
      return out;
  }
  return image;
}

std::vector<std::string> image_files(const std::string& dir) {
  static const std::vector<std::string> kExt = {".png", ".jpg", ".jpeg", ".bmp",
                                                ".pgm", ".ppm", ".tif",  ".tiff"};
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    if (!e.is_regular_file()) continue;
    std::string ext = e.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return std::tolower(c); });
    if (std::find(kExt.begin(), kExt.end(), ext) != kExt.end()) out.push_back(e.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

namespace {

class VideoFileSource final : public StoredSource {
 public:
  VideoFileSource(cv::VideoCapture cap, OutputEncoding enc) : cap_(std::move(cap)), enc_(enc) {}
  std::optional<cv::Mat> next(std::string* error) override {
    cv::Mat frame;
    if (!cap_.read(frame) || frame.empty()) {
      if (error) error->clear();
      return std::nullopt;
    }
    return to_encoding(frame, enc_);
  }
  bool skip() override { return cap_.grab(); }
  bool rewind() override { return cap_.set(cv::CAP_PROP_POS_FRAMES, 0); }
  double fps() const override { return cap_.get(cv::CAP_PROP_FPS); }
  int64_t frame_count() const override {
    const double n = cap_.get(cv::CAP_PROP_FRAME_COUNT);
    return n > 0 ? static_cast<int64_t>(n) : -1;
  }

 private:
  mutable cv::VideoCapture cap_;  // get() is not const in OpenCV
  OutputEncoding enc_;
};

class FolderSource final : public StoredSource {
 public:
  FolderSource(std::vector<std::string> files, OutputEncoding enc)
      : files_(std::move(files)), enc_(enc) {}
  std::optional<cv::Mat> next(std::string* error) override {
    if (pos_ >= files_.size()) {
      if (error) error->clear();
      return std::nullopt;
    }
    const std::string& f = files_[pos_++];
    cv::Mat img =
        cv::imread(f, enc_ == OutputEncoding::kMono8 ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
    if (img.empty()) {
      if (error) *error = f + ": not a readable image";
      return std::nullopt;
    }
    return to_encoding(img, enc_);
  }
  bool skip() override { return pos_ < files_.size() && ++pos_ > 0; }
  bool rewind() override {
    pos_ = 0;
    return true;
  }
  double fps() const override { return 0.0; }
  int64_t frame_count() const override { return static_cast<int64_t>(files_.size()); }

 private:
  std::vector<std::string> files_;
  OutputEncoding enc_;
  size_t pos_ = 0;
};

}  // namespace

std::unique_ptr<StoredSource> StoredSource::open(const SourceSpec& spec, OutputEncoding encoding,
                                                 std::string* error) {
  auto fail = [&](const std::string& why) -> std::unique_ptr<StoredSource> {
    if (error) *error = why;
    return nullptr;
  };
  std::error_code ec;
  if (spec.kind == SourceSpec::Kind::kVideoFile) {
    if (!fs::is_regular_file(spec.path, ec)) return fail(spec.path + ": no such video file");
    cv::VideoCapture cap(spec.path);
    if (!cap.isOpened()) return fail(spec.path + ": OpenCV cannot decode this video file");
    return std::make_unique<VideoFileSource>(std::move(cap), encoding);
  }
  if (spec.kind == SourceSpec::Kind::kFolder) {
    if (!fs::is_directory(spec.path, ec)) return fail(spec.path + ": no such folder");
    auto files = image_files(spec.path);
    if (files.empty()) return fail(spec.path + ": no image files (png, jpg, bmp, pgm, tif)");
    return std::make_unique<FolderSource>(std::move(files), encoding);
  }
  return fail("not a stored source");
}

FramePacer::FramePacer(double fps, int64_t start_us)
    : period_us_(static_cast<int64_t>(std::llround(1e6 / fps))), start_us_(start_us) {
  assert(fps > 0.0);
}

void FramePacer::restart(int64_t start_us) {
  start_us_ = start_us;
  next_index_ = 0;
}

FramePacer::Plan FramePacer::plan(int64_t now_us) {
  Plan p;
  const int64_t elapsed = now_us - start_us_;
  // The newest frame whose time has come; frames before it are late and skipped.
  const int64_t newest_due = elapsed >= 0 ? elapsed / period_us_ : -1;
  if (newest_due > next_index_) {
    p.skip = newest_due - next_index_;
    next_index_ = newest_due;
  }
  const int64_t due_us = start_us_ + next_index_ * period_us_;
  p.wait_us = std::max<int64_t>(0, due_us - now_us);
  ++next_index_;
  return p;
}

}  // namespace alight::camera
