// The cost of the bus's origin trailer (common/bus_auth.hpp) per message: sealing (the trailer,
// and HMAC-SHA256 when the bus is signed) on the publisher and judging on the subscriber, for a
// pose (100 Hz), an attitude command (about 430 Hz) and a 640x480 mono image (30 Hz). The peer on
// the same message: lcm-gen's encode and alight's decode_message, the work every message costs
// anyway.
//   build/bin/bench/bus_auth_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only

#include <benchmark/benchmark.h>

#include <alight/attitude_cmd_t.hpp>
#include <alight/image_t.hpp>
#include <alight/pose_t.hpp>
#include <vector>

#include "common/bus_auth.hpp"
#include "common/decode.hpp"

namespace {

using alight::bus::BusKey;
using alight::bus::Gatekeeper;
using alight::bus::Sealer;

constexpr int64_t kT0 = 1'800'000'000'000'000;

template <class M>
M sample();
template <>
alight::pose_t sample() {
  alight::pose_t m{};
  m.utime = kT0;
  m.orientation[0] = 1;
  return m;
}
template <>
alight::attitude_cmd_t sample() {
  alight::attitude_cmd_t m{};
  m.utime = kT0;
  m.armed = true;
  return m;
}
template <>
alight::image_t sample() {
  alight::image_t m{};
  m.utime = kT0;
  m.width = 640;
  m.height = 480;
  m.row_stride = 640;
  m.pixelformat = alight::image_t::PIXEL_FORMAT_GRAY;
  m.data.assign(640 * 480, 128);
  m.size = static_cast<int32_t>(m.data.size());
  return m;
}

template <class M>
std::vector<uint8_t> encoded(const M& m) {
  std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

BusKey key() { return alight::bus::make_bus_key(std::vector<uint8_t>(32, 0x5a)); }

// Peer: what a message costs without the trailer (encode + decode).
template <class M>
void BM_EncodeDecode(benchmark::State& state) {
  const M m = sample<M>();
  M out;
  for (auto _ : state) {
    auto b = encoded(m);
    benchmark::DoNotOptimize(alight::decode_message(out, b.data(), b.size()));
  }
  state.SetBytesProcessed(state.iterations() * m.getEncodedSize());
}

// Seal on the publisher, judge on the subscriber; signed or not (range 0).
template <class M>
void BM_SealAndJudge(benchmark::State& state) {
  const bool sign = state.range(0) != 0;
  const M m = sample<M>();
  const auto plain = encoded(m);
  Sealer sealer(1, sign ? std::optional<BusKey>(key()) : std::nullopt);
  Gatekeeper gate(sign ? std::optional<BusKey>(key()) : std::nullopt);
  int64_t t = kT0;
  for (auto _ : state) {
    auto b = plain;
    sealer.seal(b, "CHANNEL", ++t);
    const auto r = alight::bus::split(b.data(), b.size());
    benchmark::DoNotOptimize(gate.check("CHANNEL", r, t - kT0));
  }
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(plain.size()));
}

BENCHMARK(BM_EncodeDecode<alight::pose_t>);
BENCHMARK(BM_SealAndJudge<alight::pose_t>)->ArgName("signed")->Arg(0)->Arg(1);
BENCHMARK(BM_EncodeDecode<alight::attitude_cmd_t>);
BENCHMARK(BM_SealAndJudge<alight::attitude_cmd_t>)->ArgName("signed")->Arg(0)->Arg(1);
BENCHMARK(BM_EncodeDecode<alight::image_t>);
BENCHMARK(BM_SealAndJudge<alight::image_t>)->ArgName("signed")->Arg(0)->Arg(1);

}  // namespace

BENCHMARK_MAIN();
