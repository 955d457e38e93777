// Throughput of alight's MAVLink library: encoding one frame (unsigned and signed), and parsing
// a stream of every known message (whole, in 64-byte reads as from a serial port, signed with
// the key checked, and with noise between the frames) up to the typed messages.
//   build/bin/mavlink_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only
// Peer on the same kind of stream: node test/mavlink/conformance/mavlink_peer.mjs bench --key HEX

#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "mavlink/parser.hpp"
#include "test/mavlink/sample_messages.hpp"

namespace {

using namespace alight::mavlink;
using Bytes = std::vector<uint8_t>;

constexpr int64_t kNow = 1'767'323'045'000'000;

SigningKey bench_key() {
  SigningKey k;
  k.fill(0x5a);
  return k;
}

template <class M>
void BM_Encode(benchmark::State& state) {
  const bool sign = state.range(0) != 0;
  Sender s(1, 1, sign ? std::optional<SigningConfig>(SigningConfig{bench_key(), 1}) : std::nullopt);
  const M m = testing::distinct_message<M>(1);
  size_t bytes = 0;
  int64_t t = kNow;
  for (auto _ : state) {
    const FrameBytes f = s.pack(m, ++t);
    benchmark::DoNotOptimize(f.data.data());
    bytes += f.size;
  }
  state.SetItemsProcessed(state.iterations());
  state.SetBytesProcessed(static_cast<int64_t>(bytes));
}
BENCHMARK(BM_Encode<Heartbeat>)->ArgName("signed")->Arg(0)->Arg(1);
BENCHMARK(BM_Encode<SetAttitudeTarget>)->ArgName("signed")->Arg(0)->Arg(1);
BENCHMARK(BM_Encode<AttPosMocap>)->ArgName("signed")->Arg(0)->Arg(1);
BENCHMARK(BM_Encode<Odometry>)->ArgName("signed")->Arg(0)->Arg(1);

// 20 rounds of the 13 messages (260 frames).
struct Stream {
  Bytes bytes;
  size_t frames = 0;
};
Stream make_stream(bool sign, bool noise) {
  Sender s(1, 1, sign ? std::optional<SigningConfig>(SigningConfig{bench_key(), 1}) : std::nullopt);
  std::mt19937 rng(3);
  Stream out;
  int64_t t = kNow;
  for (int r = 0; r < 20; ++r)
    alight::mavlink::for_each_message_type([&](auto tag) {
      using M = decltype(tag);
      if (noise)
        for (int i = 0; i < 16; ++i)
          out.bytes.push_back(i % 5 == 0 ? kStxV2 : static_cast<uint8_t>(rng()));
      const FrameBytes f = s.pack(testing::distinct_message<M>(r + 1), t += 1000);
      out.bytes.insert(out.bytes.end(), f.data.begin(), f.data.begin() + f.size);
      ++out.frames;
    });
  return out;
}

// range(0): read size (0 = the whole stream at once); range(1): 1 signed; range(2): 1 noise.
void BM_Parse(benchmark::State& state) {
  const size_t read = static_cast<size_t>(state.range(0));
  const bool sign = state.range(1) != 0, noise = state.range(2) != 0;
  const Stream stream = make_stream(sign, noise);
  size_t frames = 0;
  uint64_t checksum = 0;
  for (auto _ : state) {
    ParserOptions o;
    if (sign) o.key = bench_key();
    Parser p(o);
    Frame f;
    size_t pos = 0;
    while (pos < stream.bytes.size()) {
      const size_t n = read == 0 ? stream.bytes.size() : std::min(read, stream.bytes.size() - pos);
      p.push({stream.bytes.data() + pos, n});
      pos += n;
      while (p.next(f)) {
        dispatch(f, [&](const auto& m) { checksum += sizeof(m); });
        ++frames;
      }
    }
    if (p.stats().frames_ok != stream.frames) state.SkipWithError("frames lost");
  }
  benchmark::DoNotOptimize(checksum);
  state.SetItemsProcessed(static_cast<int64_t>(frames));
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * stream.bytes.size()));
}
BENCHMARK(BM_Parse)
    ->ArgNames({"read", "signed", "noise"})
    ->Args({0, 0, 0})
    ->Args({64, 0, 0})
    ->Args({1, 0, 0})
    ->Args({64, 1, 0})
    ->Args({64, 0, 1})
    ->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
