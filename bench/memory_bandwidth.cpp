// Memory bandwidth of the OpenCL device (copy and STREAM triad kernels) and of the host
// (memcpy), for the roofline of the contact sweeps in bench/RESULTS.md.
//   build/bench/memory_bandwidth --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cstring>
#include <vector>

#include "host/device.hpp"

namespace {

// 64 Mi float4 = 1 GiB per buffer would not fit every device; 16 Mi float4 = 256 MiB does,
// and is far larger than any cache
constexpr int kItems = 16 << 20;

talus::Device& device() {
  static talus::Device dev;
  return dev;
}

void DeviceCopy(benchmark::State& state) {
  talus::Device& dev = device();
  talus::Buffer<cl_float4> in(dev, kItems), out(dev, kItems);
  cl_float4 zero{};
  in.fill(zero);
  cl::Kernel k = dev.kernel(dev.program({"bandwidth.cl"}), "bandwidth_copy");
  talus::set_args(k, in, out, kItems);
  for (auto _ : state) {
    talus::launch(dev, k, kItems, "bandwidth_copy");
    dev.finish();
  }
  state.SetBytesProcessed(int64_t(state.iterations()) * kItems * 32);
}
BENCHMARK(DeviceCopy)->Unit(benchmark::kMillisecond)->UseRealTime();

void DeviceTriad(benchmark::State& state) {
  talus::Device& dev = device();
  talus::Buffer<cl_float4> a(dev, kItems), b(dev, kItems), c(dev, kItems);
  cl_float4 one{{1.0f, 1.0f, 1.0f, 1.0f}};
  b.fill(one);
  c.fill(one);
  cl::Kernel k = dev.kernel(dev.program({"bandwidth.cl"}), "bandwidth_triad");
  talus::set_args(k, a, b, c, 3.0f, kItems);
  for (auto _ : state) {
    talus::launch(dev, k, kItems, "bandwidth_triad");
    dev.finish();
  }
  state.SetBytesProcessed(int64_t(state.iterations()) * kItems * 48);
}
BENCHMARK(DeviceTriad)->Unit(benchmark::kMillisecond)->UseRealTime();

// the cost of one launch of a small kernel, as the PGS sweep makes them: one per colour and
// sweep, each over about a colour's rows (a D200 dig: ~30,000 contacts in ~20 colours, so
// ~1,500 items). 100 launches on the in-order queue, then one wait; time per launch
void DeviceLaunch(benchmark::State& state) {
  talus::Device& dev = device();
  const int items = static_cast<int>(state.range(0));
  talus::Buffer<cl_float4> in(dev, items), out(dev, items);
  cl_float4 zero{};
  in.fill(zero);
  cl::Kernel k = dev.kernel(dev.program({"bandwidth.cl"}), "bandwidth_copy");
  talus::set_args(k, in, out, items);
  constexpr int kLaunches = 100;
  for (auto _ : state) {
    for (int i = 0; i < kLaunches; ++i) talus::launch(dev, k, items, "bandwidth_copy");
    dev.finish();
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * kLaunches);
}
BENCHMARK(DeviceLaunch)
    ->Arg(64)
    ->Arg(1536)
    ->Arg(16384)
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

// what a host wait costs: eight small transfers (64 float4, a type-G zone's particle array) each
// waited for (the blocking calls of talus::Buffer), against the same eight enqueued without a
// wait and one finish at the end. On PoCL a wait is a hand-over between the host thread and the
// device's worker threads (bench/RESULTS.md 2026-11-28 "host waits")
void DeviceTransfers(benchmark::State& state) {
  talus::Device& dev = device();
  const bool blocking = state.range(0) != 0;
  constexpr int kTransfers = 8, kItemsEach = 64;
  talus::Buffer<cl_float4> buffer(dev, kItemsEach);
  std::vector<std::vector<cl_float4>> host(kTransfers, std::vector<cl_float4>(kItemsEach));
  const size_t bytes = kItemsEach * sizeof(cl_float4);
  for (auto _ : state) {
    for (int k = 0; k < kTransfers; ++k) {
      const cl_bool wait = blocking ? CL_TRUE : CL_FALSE;
      if (k % 2 == 0)
        dev.queue().enqueueWriteBuffer(buffer.raw(), wait, 0, bytes, host[k].data());
      else
        dev.queue().enqueueReadBuffer(buffer.raw(), wait, 0, bytes, host[k].data());
    }
    dev.finish();
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * kTransfers);
}
BENCHMARK(DeviceTransfers)->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond)->UseRealTime();

void HostMemcpy(benchmark::State& state) {
  std::vector<char> src(size_t(kItems) * 16, 1), dst(size_t(kItems) * 16);
  for (auto _ : state) {
    std::memcpy(dst.data(), src.data(), src.size());
    benchmark::DoNotOptimize(dst.data());
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(src.size()) * 2);
}
BENCHMARK(HostMemcpy)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
