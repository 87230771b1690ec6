#include "host/device.hpp"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <system_error>

#include "host/embedded.hpp"
#include "host/error.hpp"
#include "host/files.hpp"
#include "host/program_cache.hpp"

namespace talus {

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

bool contains(const std::string& hay, const std::string& needle) {
  return needle.empty() || lower(hay).find(lower(needle)) != std::string::npos;
}

constexpr const char* kInstallHint =
    "no OpenCL platform found. Install one: on Debian/Ubuntu `sudo apt-get install "
    "pocl-opencl-icd ocl-icd-libopencl1` runs talus on the CPU; for a GPU install the vendor's "
    "OpenCL driver (e.g. nvidia-opencl-icd). `clinfo -l` lists what is installed.";

// PoCL keeps its compiled kernels in POCL_CACHE_DIR; a folder it cannot write makes it report no
// platform or a failed kernel build, neither naming the folder, so talus checks it first
void check_pocl_cache_dir() {
  const char* dir = std::getenv("POCL_CACHE_DIR");
  if (dir == nullptr || *dir == '\0') return;
  const std::string hint =
      std::string("POCL_CACHE_DIR=") + dir + ": PoCL cannot keep its compiled kernels there (";
  const std::string fix =
      "); point POCL_CACHE_DIR at a writable folder (scripts and ctest use build/pocl-cache) or "
      "unset it";
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (!std::filesystem::is_directory(dir, ec))
    throw InputError(hint + "not a folder, and none can be made" + fix);
  const std::filesystem::path probe = std::filesystem::path(dir) / ".talus-write-check";
  const bool writable = static_cast<bool>(std::ofstream(probe));
  std::filesystem::remove(probe, ec);
  if (!writable) throw InputError(hint + "the folder is not writable" + fix);
}

}  // namespace

DeviceChoice device_choice_from_env() {
  DeviceChoice choice;
  if (const char* env = std::getenv("TALUS_DEVICE")) {
    std::string s(env);
    auto colon = s.find(':');
    choice.platform = s.substr(0, colon);
    if (colon != std::string::npos) choice.device = s.substr(colon + 1);
  }
  return choice;
}

void list_pocl_in_thread_device() {
  // overwrite 0: a user's POCL_DEVICES wins
  setenv("POCL_DEVICES", "pthread basic", 0);
}

bool runs_in_calling_thread(const std::string& platform, const std::string& device) {
  // PoCL names its devices after the driver: "basic-<cpu>" (PoCL 5: "cpu-minimal-<cpu>") runs
  // commands in the thread that flushes or waits for them, "pthread-<cpu>" ("cpu-<cpu>") in a
  // pool of worker threads
  const std::string name = lower(device);
  return contains(platform, "Portable Computing Language") &&
         (name.rfind("basic", 0) == 0 || name.rfind("cpu-minimal", 0) == 0);
}

std::vector<size_t> candidate_order(const std::vector<DeviceKind>& kinds, bool in_host_thread) {
  std::vector<size_t> order(kinds.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = k;
  // GPUs first; among the rest the preferred kind of CPU device, each in listing order
  auto rank = [&](size_t k) {
    return kinds[k].gpu ? 0 : (kinds[k].in_thread == in_host_thread ? 1 : 2);
  };
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return rank(a) < rank(b); });
  return order;
}

Device::Device(const DeviceChoice& choice) {
  check_pocl_cache_dir();
  std::vector<cl::Platform> platforms;
  try {
    cl::Platform::get(&platforms);
  } catch (const cl::Error&) {
    platforms.clear();
  }
  if (platforms.empty()) throw Error(kInstallHint);

  // candidates: every device of every matching platform, taken in candidate_order
  struct Candidate {
    cl::Platform platform;
    cl::Device device;
    DeviceKind kind;
  };
  std::vector<Candidate> candidates;
  std::string seen;
  for (auto& p : platforms) {
    std::string pname = p.getInfo<CL_PLATFORM_NAME>();
    std::vector<cl::Device> devices;
    try {
      p.getDevices(CL_DEVICE_TYPE_ALL, &devices);
    } catch (const cl::Error&) {
      continue;
    }
    for (auto& d : devices) {
      std::string dname = d.getInfo<CL_DEVICE_NAME>();
      seen += "\n  " + pname + " : " + dname;
      if (!contains(pname, choice.platform) || !contains(dname, choice.device)) continue;
      candidates.push_back({p,
                            d,
                            {(d.getInfo<CL_DEVICE_TYPE>() & CL_DEVICE_TYPE_GPU) != 0,
                             runs_in_calling_thread(pname, dname)}});
    }
  }

  if (candidates.empty()) {
    if (seen.empty()) throw Error(kInstallHint);
    throw Error("no OpenCL device matches TALUS_DEVICE / DeviceChoice (platform '" + choice.platform +
                "', device '" + choice.device + "'); available:" + seen +
                "\nfix: set TALUS_DEVICE=platform-substring:device-substring, or unset it");
  }

  std::vector<DeviceKind> kinds;
  kinds.reserve(candidates.size());
  for (const Candidate& k : candidates) kinds.push_back(k.kind);
  const Candidate& c = candidates[candidate_order(kinds, choice.in_host_thread).front()];
  device_ = c.device;
  is_gpu_ = c.kind.gpu;
  is_cpu_ = cl_checked("querying the device's type", [&] {
    return (device_.getInfo<CL_DEVICE_TYPE>() & CL_DEVICE_TYPE_CPU) != 0;
  });
  compute_units_ = static_cast<int>(cl_checked("querying the device's compute units", [&] {
    return device_.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>();
  }));
  cl_checked("creating the context and queue", [&] {
    context_ = cl::Context(device_);
    queue_ = cl::CommandQueue(context_, device_);
    return 0;
  });
  std::ostringstream os;
  os << c.platform.getInfo<CL_PLATFORM_NAME>() << " / " << device_.getInfo<CL_DEVICE_NAME>() << " ("
     << device_.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>() << " compute units, "
     << (device_.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>() >> 20) << " MiB)";
  description_ = os.str();
  platform_identity_ =
      c.platform.getInfo<CL_PLATFORM_NAME>() + " | " + c.platform.getInfo<CL_PLATFORM_VERSION>();
  device_identity_ = device_.getInfo<CL_DEVICE_NAME>() + " | " +
                     device_.getInfo<CL_DEVICE_VERSION>() + " | " +
                     device_.getInfo<CL_DRIVER_VERSION>();
}

const cl::Program& Device::program(const std::vector<std::string>& files, const std::string& options) {
  std::string key = options;
  for (auto& f : files) key += "|" + f;
  auto it = programs_.find(key);
  if (it != programs_.end()) return it->second;

  // shared headers (*.h, host/kernel data layouts) come first, in name order
  std::string source;
  for (auto& e : embedded_sources()) {
    std::string name = e.name;
    if (name.size() > 2 && name.compare(name.size() - 2, 2, ".h") == 0) source += e.text + "\n";
  }
  for (auto& f : files) source += embedded_source(f) + "\n";
  // a CPU device's kernels may use CPU-only hints (TL_PREFETCH, kernels/common.h)
  const std::string build_options =
      std::string("-cl-std=CL1.2 ") + (is_cpu_ ? "-DTL_CPU_DEVICE " : "") + options;

  // the binary a former run saved for this very source, options and driver, if the driver takes
  // it back; anything else builds the source
  const std::string cache_dir = default_cache_dir();
  const std::string cache_key =
      program_cache_key(source, build_options, platform_identity_, device_identity_);
  if (std::optional<std::string> binary = read_program_binary(cache_dir, cache_key)) {
    try {
      cl::Program::Binaries binaries{std::vector<unsigned char>(binary->begin(), binary->end())};
      cl::Program cached(context_, std::vector<cl::Device>{device_}, binaries);
      cached.build(std::vector<cl::Device>{device_}, build_options.c_str());
      return programs_.emplace(key, std::move(cached)).first->second;
    } catch (const cl::Error&) {
      // refused (another driver build under the same version string): from source below
    }
  }

  cl::Program program(context_, source);
  try {
    program.build(std::vector<cl::Device>{device_}, build_options.c_str());
  } catch (const cl::Error& e) {
    std::string log;
    try {
      log = program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(device_);
    } catch (const cl::Error&) {
      log = "(no build log)";
    }
    std::string names;
    for (auto& f : files) names += f + " ";
    throw Error("OpenCL: building kernels " + names + "failed with " + cl_status_name(e.err()) +
                "; build log:\n" + log);
  }
  // its binary for the next run (a cache that cannot be written only loses that)
  if (!cache_dir.empty()) {
    try {
      const auto binaries = program.getInfo<CL_PROGRAM_BINARIES>();
      if (binaries.size() == 1)
        save_program_binary(cache_dir, cache_key,
                            std::string(binaries[0].begin(), binaries[0].end()));
    } catch (const cl::Error&) {
      // a driver without binaries: nothing to keep
    }
  }
  return programs_.emplace(key, std::move(program)).first->second;
}

cl::Kernel Device::kernel(const cl::Program& program, const char* name) {
  return cl_checked(name, [&] { return cl::Kernel(program, name); });
}

void Device::finish() {
  cl_checked("waiting for the queue", [&] { return queue_.finish(); });
}

void launch(Device& dev, cl::Kernel& kernel, size_t count, const char* what) {
  if (count == 0) return;
  size_t global = (count + kWorkGroupSize - 1) / kWorkGroupSize * kWorkGroupSize;
  cl_checked(what, [&] {
    return dev.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(global),
                                            cl::NDRange(kWorkGroupSize));
  });
}

void launch_walks(Device& dev, cl::Kernel& kernel, size_t groups, const char* what) {
  if (groups == 0) return;
  cl_checked(what, [&] {
    return dev.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(groups),
                                            cl::NDRange(1));
  });
}

void launch_group(Device& dev, cl::Kernel& kernel, size_t size, const char* what) {
  cl_checked(what, [&] {
    return dev.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(size),
                                            cl::NDRange(size));
  });
}

}  // namespace talus
