// host/device: device discovery, program builds from embedded sources, error reporting, the
// buffers' transfers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "host/device.hpp"
#include "host/embedded.hpp"

namespace talus {
namespace {

TEST(Device, DefaultDeviceIsFoundAndDescribed) {
  Device dev;
  EXPECT_FALSE(dev.description().empty());
}

TEST(Device, UnknownDeviceNameGivesAClearError) {
  try {
    Device dev(DeviceChoice{"no-such-platform-xyz", ""});
    FAIL() << "expected an error";
  } catch (const Error& e) {
    std::string msg = e.what();
    EXPECT_NE(msg.find("TALUS_DEVICE"), std::string::npos) << msg;
    EXPECT_NE(msg.find("available"), std::string::npos) << msg;
  }
}

// PoCL's in-thread device is known by its driver's name, and only PoCL's
TEST(Device, PoclsInThreadDeviceIsKnownByItsName) {
  const std::string pocl = "Portable Computing Language";
  EXPECT_TRUE(runs_in_calling_thread(pocl, "basic-skylake-avx512-Intel(R) Xeon(R) Processor"));
  EXPECT_FALSE(runs_in_calling_thread(pocl, "pthread-skylake-avx512-Intel(R) Xeon(R) Processor"));
  // PoCL 5's names of the same two drivers
  EXPECT_TRUE(
      runs_in_calling_thread(pocl, "cpu-minimal-skylake-avx512-Intel(R) Xeon(R) Processor"));
  EXPECT_FALSE(runs_in_calling_thread(pocl, "cpu-skylake-avx512-Intel(R) Xeon(R) Processor"));
  EXPECT_FALSE(runs_in_calling_thread("NVIDIA CUDA", "basic"));
}

// the order candidates are taken in: GPUs first, then the preferred kind of CPU device, each kind
// in listing order (PoCL lists `basic` before `pthread`: without the preference it comes last)
TEST(Device, CandidatesAreTakenGpusFirstThenThePreferredKindOfCpuDevice) {
  const DeviceKind basic{false, true}, pthread{false, false}, gpu{true, false};
  using Order = std::vector<size_t>;
  EXPECT_EQ(candidate_order({basic, pthread}, false), (Order{1, 0}));
  EXPECT_EQ(candidate_order({basic, pthread}, true), (Order{0, 1}));
  EXPECT_EQ(candidate_order({pthread, basic}, true), (Order{1, 0}));
  EXPECT_EQ(candidate_order({basic, pthread, gpu}, true), (Order{2, 0, 1}));
  EXPECT_EQ(candidate_order({pthread, gpu, basic, gpu}, false), (Order{1, 3, 0, 2}));
  EXPECT_EQ(candidate_order({pthread}, true), (Order{0}));
  EXPECT_EQ(candidate_order({}, true), Order{});
}

// on this machine's devices: the preference takes an in-thread device when the matching list has
// one and no GPU, and otherwise the device the default choice takes
TEST(Device, APreferenceForTheCallingThreadFallsBackToTheDefaultDevice) {
  DeviceChoice choice = device_choice_from_env();
  bool gpu = false, in_thread = false;
  std::vector<cl::Platform> platforms;
  cl::Platform::get(&platforms);
  for (const cl::Platform& p : platforms) {
    std::vector<cl::Device> devices;
    p.getDevices(CL_DEVICE_TYPE_ALL, &devices);
    for (const cl::Device& d : devices) {
      const std::string pname = p.getInfo<CL_PLATFORM_NAME>(), dname = d.getInfo<CL_DEVICE_NAME>();
      // TALUS_DEVICE's substrings, case-insensitive as Device matches them
      auto has = [](std::string hay, std::string needle) {
        for (auto* t : {&hay, &needle})
          std::transform(t->begin(), t->end(), t->begin(),
                         [](unsigned char c) { return std::tolower(c); });
        return hay.find(needle) != std::string::npos;
      };
      if (!has(pname, choice.platform) || !has(dname, choice.device)) continue;
      gpu = gpu || (d.getInfo<CL_DEVICE_TYPE>() & CL_DEVICE_TYPE_GPU) != 0;
      in_thread = in_thread || runs_in_calling_thread(pname, dname);
    }
  }
  choice.in_host_thread = true;
  const Device preferred(choice);
  const Device usual;
  if (!in_thread || gpu) {
    EXPECT_EQ(preferred.description(), usual.description());
  } else {
    EXPECT_NE(preferred.description(), usual.description());
  }
}

TEST(Device, MissingKernelFileIsNamed) {
  try {
    embedded_source("does_not_exist.cl");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("does_not_exist.cl"), std::string::npos);
  }
}

// an upload does not wait for its write: the buffer writes from its own copy, so the caller's
// vector may change (or go) at once; uploads in a row, a move, and reads enqueued behind one wait
// all see what was uploaded, in order (fresh random data each run)
TEST(Buffer, UploadsWriteWhatWasGivenThoughTheCallerReusesItsVector) {
  Device dev;
  std::mt19937 rng(std::random_device{}());
  std::uniform_int_distribution<int> value(-1000000, 1000000);
  constexpr size_t kCount = 10000;
  std::vector<int> host(kCount), first(kCount), second(kCount);
  for (int& x : first) x = value(rng);
  for (int& x : second) x = value(rng);
  Buffer<int> a(dev, kCount), b(dev, kCount);
  // the vector handed to the upload is overwritten before anything waits
  host = first;
  a.upload(host);
  host = second;
  b.upload(host);
  std::fill(host.begin(), host.end(), 0);
  EXPECT_EQ(a.download(), first);
  EXPECT_EQ(b.download(), second);
  // a second upload to the same buffer (its copy reused) and a move keep the last one's data
  a.upload(second);
  a.upload(first);
  Buffer<int> moved = std::move(a);
  EXPECT_EQ(moved.download(), first);
  // two reads enqueued, one wait
  std::vector<int> x, y;
  PendingReads reads(dev);
  moved.enqueue_download(x, kCount);
  b.enqueue_download(y, kCount / 2);
  reads.wait();
  EXPECT_EQ(x, first);
  EXPECT_EQ(y, std::vector<int>(second.begin(), second.begin() + kCount / 2));
}

}  // namespace
}  // namespace talus
