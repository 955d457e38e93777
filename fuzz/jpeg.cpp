// The JPEG path of image_from_msg with the fuzzer's bytes as the compressed frame, so that
// mutations go into the JPEG structure rather than the image_t around it. The first 4 bytes give
// the message's width and height (0 = not stated, as a camera may send), the rest is the JPEG.
#include "common/image_msg.hpp"
#include "fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  if (size < 4) return 0;
  image_t msg{};
  msg.utime = 1;
  msg.pixelformat = image_t::PIXEL_FORMAT_MJPEG;
  msg.width = (data[0] << 8) | data[1];
  msg.height = (data[2] << 8) | data[3];
  msg.data.assign(data + 4, data + size);
  msg.size = static_cast<int32_t>(msg.data.size());
  std::string error;
  (void)image_from_msg(msg, true, &error);
  (void)image_from_msg(msg, false, &error);
  return 0;
}
