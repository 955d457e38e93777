// One captured V4L2 buffer through the camera driver's conversion (camera_driver/convert.hpp): a
// USB camera's corrupt or short buffers and MJPEG frames. The first 8 bytes give the negotiated
// format (GREY / YUYV / MJPEG), width, height and stride as the driver reports them; the rest is
// the buffer. Every output encoding is tried.
#include "camera_driver/convert.hpp"
#include "fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight::camera;
  if (size < 8) return 0;
  RawFrameView frame;
  frame.format = data[0] % 3 == 0 ? PixelFormat::kGrey
                                  : (data[0] % 3 == 1 ? PixelFormat::kYuyv : PixelFormat::kMjpeg);
  frame.width = ((data[1] << 8) | data[2]) % 4097;
  frame.height = ((data[3] << 8) | data[4]) % 4097;
  frame.stride = (data[5] << 8) | data[6];
  (void)data[7];
  frame.data = data + 8;
  frame.bytes = size - 8;
  cv::Mat out;
  std::string error;
  for (OutputEncoding e : {OutputEncoding::kMono8, OutputEncoding::kRgb8, OutputEncoding::kBgr8})
    (void)convert_frame(frame, e, out, &error);
  return 0;
}
