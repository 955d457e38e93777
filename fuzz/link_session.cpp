// alight-link's protocol on arbitrary bytes (link/protocol.hpp): from a stranger before any
// hello, and inside a session both sides opened genuinely: never a crash, never more held than
// one frame, and nothing delivered from a stranger before it proved the key.
#include "fuzz/fuzz_support.hpp"
#include "link/protocol.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight::link;
  const auto key = alight::bus::make_bus_key(std::vector<uint8_t>(32, 0x33));
  Nonce nv{}, ng{};
  nv.fill(1);
  ng.fill(2);
  const std::span<const uint8_t> input(data, size);
  std::vector<Message> out;
  {
    Session stranger_facing(key, Role::kVehicle, nv, 1 << 16);
    stranger_facing.feed(input, out);
    if (!out.empty()) __builtin_trap();  // no DATA before READY
  }
  Session vehicle(key, Role::kVehicle, nv, 1 << 16), ground(key, Role::kGround, ng, 1 << 16);
  const auto hv = vehicle.hello(), hg = ground.hello();
  vehicle.feed(hg, out);
  ground.feed(hv, out);
  const auto cv = vehicle.take_control(), cg = ground.take_control();
  ground.feed(cv, out);
  vehicle.feed(cg, out);
  if (!vehicle.open() || !ground.open()) __builtin_trap();
  vehicle.feed(input, out);
  return 0;
}
