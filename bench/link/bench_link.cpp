// Speed of the DUT link's host-side parts (docs/can-protocol.md, "Measured"):
// codec, reassembly, and the whole in-process lockstep path (firmware emulator
// -> in-process bus -> CanDutLink) that the emulated plant runs 110 minutes of.
#include <benchmark/benchmark.h>

#include <vector>

#include "firmware_link/dbc_stream.hpp"
#include "firmware_link/protocol.hpp"
#include "firmware_link/reassembly.hpp"
#include "plant/firmware/inprocess_dut.hpp"
#include "tests/link/test_support.hpp"

using namespace rig;
using namespace rig::link;

static void BM_CodecStreamHalfRoundTrip(benchmark::State& st) {
  uint32_t seq = 0;
  for (auto _ : st) {
    const Decoded d = decode(encode(StreamHalf{Channel::X, seq++, 1, 1.5f}));
    benchmark::DoNotOptimize(d);
  }
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_CodecStreamHalfRoundTrip);

// A DBC-described stream's decoder on the rig protocol's frames (the codec's job, done
// through docs/rig-dut.dbc): frames per second of host CPU.
static void BM_DbcStreamDecodeFrame(benchmark::State& st) {
  const DbcStreamDecoder dec(rig_protocol_dbc(), rig_protocol_stream(), "bench");
  std::vector<StreamPart> parts;
  uint32_t seq = 0;
  for (auto _ : st) {
    parts.clear();
    dec.decode(encode(StreamHalf{(seq & 1) ? Channel::Y : Channel::X, seq & kSeqMask, 1, 1.5f}), parts);
    ++seq;
    benchmark::DoNotOptimize(parts.data());
  }
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_DbcStreamDecodeFrame);

static void BM_ReassemblySamples(benchmark::State& st) {
  StreamReassembler r;
  std::vector<Sample> out(1000);
  uint32_t seq = 0;
  for (auto _ : st) {
    for (int i = 0; i < 1000; ++i, ++seq) {
      r.push({Channel::X, seq & kSeqMask, 1, 0.5f});
      r.push({Channel::Y, seq & kSeqMask, 1, 0.25f});
    }
    benchmark::DoNotOptimize(r.pop(out));
  }
  st.SetItemsProcessed(st.iterations() * 1000);  // samples
}
BENCHMARK(BM_ReassemblySamples);

// Samples per second of host CPU through the real protocol in lockstep: the
// emulated plant's 110-minute procedure is 6.6 million of them.
static void BM_InProcessLockstepStream(benchmark::State& st) {
  link::testing::RampSource src;
  SimClock clock;
  auto dut = make_inprocess_dut(src, clock);
  clock.set_advance([&](double dt) { dut->step(dt); });
  dut->start_stream({});
  std::vector<Sample> v(10000);
  for (auto _ : st) benchmark::DoNotOptimize(dut->read(v, {}));
  st.SetItemsProcessed(st.iterations() * static_cast<int64_t>(v.size()));
}
BENCHMARK(BM_InProcessLockstepStream)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
