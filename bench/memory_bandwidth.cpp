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
