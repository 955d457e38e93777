// The origin trailer on arbitrary bytes (common/bus_auth.hpp): split never reads outside the
// buffer, the gatekeeper (unsigned and signed) never throws and keeps bounded state whatever the
// publisher ids, and what decodes as a pose goes through the pose innovation gate.
#include "common/bus_auth.hpp"
#include "common/msg_convert.hpp"
#include "common/pose_gate.hpp"
#include "fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  // Across inputs, as a node's state lives across messages.
  static bus::Gatekeeper unsigned_gate;
  static bus::Gatekeeper signed_gate(bus::make_bus_key(std::vector<uint8_t>(32, 0x5a)));
  static PoseGate pose_gate;
  static int64_t steady_us = 0;
  steady_us += 1000;
  const bus::Received r = bus::split(data, size);
  for (auto* gate : {&unsigned_gate, &signed_gate})
    for (const char* channel : {"MOCAP_POSE", "NODE_STATUS"}) {
      (void)gate->check(channel, r, steady_us, channel[0] == 'M');
      if (gate->known_sources(channel) > bus::kMaxSourcesPerChannel) __builtin_trap();
    }
  if (const auto msg = fuzz::decode<pose_t>(data, size)) {
    std::string why;
    if (const auto pose = pose_from_msg(*msg, &why)) (void)pose_gate.check(*pose);
  }
  return 0;
}
