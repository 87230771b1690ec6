// The OpenCL runtime: device choice, context and in-order queue, typed buffers,
// programs built from the embedded kernel sources, and kernel launches.
//
// Every OpenCL failure surfaces as talus::Error naming the call, the status code
// and, for program builds, the compiler's build log.
#pragma once
#include <CL/opencl.hpp>

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "host/error.hpp"

namespace talus {

class StageTimes;

// which device to use: substrings of the platform and device names (case-insensitive);
// empty strings take the default, the first GPU if any, else the first CPU device
struct DeviceChoice {
  std::string platform;
  std::string device;
  // among the CPU devices that match, prefer one that runs the kernels in the calling thread
  // (PoCL's `basic`) to one that hands every command to worker threads (PoCL's `pthread`, else
  // the default): a system of a few hundred particles spends more in the hand-overs than in its
  // kernels (HD27-G200 0.66 of the time, the same bits; bench/RESULTS.md 2026-11-28 "in the host
  // thread"). PoCL lists `basic` only where POCL_DEVICES names it (list_pocl_in_thread_device);
  // without one this changes nothing. GPUs still come first
  bool in_host_thread = false;
};

// reads TALUS_DEVICE ("platform-substring:device-substring", either part may be empty)
DeviceChoice device_choice_from_env();

// has PoCL list its in-thread device (`basic`) beside its threaded one (`pthread`), by setting
// POCL_DEVICES="pthread basic" unless the user set POCL_DEVICES. That list replaces PoCL's own
// (a GPU PoCL drives would no longer be listed), and it takes effect only before the process's
// first OpenCL call (PoCL reads it once): the command-line tool calls it only for a run whose
// choice prefers the calling thread, just before it makes the Device
void list_pocl_in_thread_device();

// is `device` of `platform` one that runs kernels in the calling thread? PoCL's `basic`
// ("basic-<cpu>", named `cpu-minimal` from PoCL 5)
bool runs_in_calling_thread(const std::string& platform, const std::string& device);

// what the device choice orders candidates by
struct DeviceKind {
  bool gpu = false;
  bool in_thread = false;  // runs kernels in the calling thread
};
// the order in which the candidates are taken (indices into `kinds`, the first is used): GPUs
// first; among the others, those running in the calling thread first where `in_host_thread`,
// else last; otherwise in listing order
std::vector<size_t> candidate_order(const std::vector<DeviceKind>& kinds, bool in_host_thread);

// runs an OpenCL C++-binding call; converts cl::Error into talus::Error naming `what`
template <class F>
auto cl_checked(const char* what, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const cl::Error& e) {
    throw Error(std::string("OpenCL: ") + what + " failed in " + e.what() + " with " +
                cl_status_name(e.err()) + " (" + std::to_string(e.err()) + ")");
  }
}

class Device {
 public:
  explicit Device(const DeviceChoice& choice = device_choice_from_env());

  const cl::Context& context() const { return context_; }
  const cl::CommandQueue& queue() const { return queue_; }
  const cl::Device& device() const { return device_; }
  bool is_gpu() const { return is_gpu_; }
  // a CPU device (CL_DEVICE_TYPE_CPU, PoCL here): it runs a work-group's items one after another
  // on one core, so a barrier costs a turn of every item, and kernels with barriers over mostly
  // idle items (the one-group sweeps, short scans) take one work-item there instead
  bool is_cpu() const { return is_cpu_; }
  // the device's compute units (CL_DEVICE_MAX_COMPUTE_UNITS): cores of a CPU device
  int compute_units() const { return compute_units_; }
  // "platform / device (compute units, global memory)"
  std::string description() const { return description_; }
  // the device's global memory [bytes] (CL_DEVICE_GLOBAL_MEM_SIZE), what its buffers share
  std::size_t global_memory() const { return device_.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>(); }
  // the largest single buffer it allocates [bytes] (CL_DEVICE_MAX_MEM_ALLOC_SIZE)
  std::size_t max_allocation() const { return device_.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>(); }

  // a program made of the shared headers followed by `files` (names in kernels/);
  // built once per Device and option string, and kept; created from the binary a former run
  // saved in default_cache_dir()/kernels when one is there for this very source, options and
  // driver (host/program_cache.hpp), else built from source and its binary saved
  const cl::Program& program(const std::vector<std::string>& files, const std::string& options = "");
  // a fresh kernel object from a program (kernels carry their arguments, so callers own them)
  cl::Kernel kernel(const cl::Program& program, const char* name);

  // waits for all enqueued work
  void finish();

  // profiling of the step's stages (host/stage_times.hpp): while `times` is set (not owned, must
  // outlive its use), every StageScope on this device drains the queue and charges its time
  // there; nullptr (the default) turns profiling off
  void set_stage_times(StageTimes* times) { stage_times_ = times; }
  StageTimes* stage_times() const { return stage_times_; }

 private:
  cl::Context context_;
  cl::Device device_;
  cl::CommandQueue queue_;
  bool is_gpu_ = false;
  bool is_cpu_ = false;
  int compute_units_ = 1;
  std::string description_;
  // the platform's and device's names and versions and the driver's: what a program binary is
  // built for (host/program_cache.hpp)
  std::string platform_identity_, device_identity_;
  std::map<std::string, cl::Program> programs_;
  StageTimes* stage_times_ = nullptr;
};

// a device array of trivially copyable T; contents are lost on resize
template <class T>
class Buffer {
 public:
  Buffer() = default;
  Buffer(Device& dev, size_t count) : dev_(&dev) { resize(count); }
  // an upload may still be reading the buffer's staging copy: it is waited for before the copy
  // goes (a buffer is moved, never copied: two owners of one staging copy could not tell)
  ~Buffer() { wait_for_upload(false); }
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  Buffer(Buffer&& other) noexcept { *this = std::move(other); }
  Buffer& operator=(Buffer&& other) noexcept {
    wait_for_upload(false);
    dev_ = other.dev_;
    buffer_ = std::move(other.buffer_);
    count_ = std::exchange(other.count_, 0);
    capacity_ = std::exchange(other.capacity_, 0);
    staging_ = std::move(other.staging_);
    upload_ = std::move(other.upload_);
    uploading_ = other.uploading_;
    other.uploading_ = false;
    return *this;
  }

  size_t size() const { return count_; }
  // the device memory it holds [bytes]: its capacity, which grows ahead of its size
  size_t bytes() const { return capacity_ * sizeof(T); }
  const cl::Buffer& raw() const { return buffer_; }

  // reallocates when the capacity is too small (grows by 1.5x to amortise)
  void resize(size_t count) {
    count_ = count;
    if (count <= capacity_ && capacity_ > 0) return;
    capacity_ = std::max<size_t>(1, count + count / 2);
    buffer_ = cl_checked("allocating a device buffer", [&] {
      return cl::Buffer(dev_->context(), CL_MEM_READ_WRITE, capacity_ * sizeof(T));
    });
  }
  // enqueues the write without waiting for it: the data go through the buffer's own staging copy,
  // which the write reads until the queue reaches it, so the caller's vector is free at once. A
  // wait is a hand-over between the host and the device's threads on PoCL (about 10 us, several
  // per type-G step: bench/RESULTS.md 2026-11-28 "host waits"); the in-order queue runs the write
  // before every later command, and the next upload waits for this one before reusing the copy.
  // The copy stays until then: the host holds each uploaded array twice (the particle arrays: 64 B
  // a particle, 29 MB at D50)
  void upload(const std::vector<T>& host) {
    resize(host.size());
    if (host.empty()) return;
    wait_for_upload(true);
    staging_.assign(host.begin(), host.end());
    cl_checked("uploading a buffer", [&] {
      return dev_->queue().enqueueWriteBuffer(buffer_, CL_FALSE, 0, staging_.size() * sizeof(T),
                                              staging_.data(), nullptr, &upload_);
    });
    uploading_ = true;
  }
  std::vector<T> download() const { return download(count_); }
  std::vector<T> download(size_t count) const {
    std::vector<T> host(count);
    if (count == 0) return host;
    cl_checked("downloading a buffer", [&] {
      dev_->queue().enqueueReadBuffer(buffer_, CL_TRUE, 0, count * sizeof(T), host.data());
    });
    return host;
  }
  // enqueues the read of the first `count` elements into `host` without waiting: they are there
  // after the queue's next wait, and `host` must live until then, also when an error unwinds the
  // stack: declare the vectors, then a PendingReads, and end with its wait(). Several reads then
  // one wait cost one hand-over instead of one each (DemWorld::particles)
  void enqueue_download(std::vector<T>& host, size_t count) const {
    host.resize(count);
    if (count == 0) return;
    cl_checked("downloading a buffer", [&] {
      return dev_->queue().enqueueReadBuffer(buffer_, CL_FALSE, 0, count * sizeof(T), host.data());
    });
  }
  T read_one(size_t index) const {
    T value;
    cl_checked("reading one element", [&] {
      dev_->queue().enqueueReadBuffer(buffer_, CL_TRUE, index * sizeof(T), sizeof(T), &value);
    });
    return value;
  }
  void fill(const T& value) {
    if (count_ == 0) return;
    cl_checked("filling a buffer", [&] {
      dev_->queue().enqueueFillBuffer(buffer_, value, 0, count_ * sizeof(T));
    });
  }
  void copy_from(const Buffer<T>& other) {
    resize(other.size());
    if (count_ == 0) return;
    cl_checked("copying a buffer", [&] {
      dev_->queue().enqueueCopyBuffer(other.raw(), buffer_, 0, 0, count_ * sizeof(T));
    });
  }

 private:
  // `report`: a failed write throws; a destructor or a move cannot, and leaves it to the queue's
  // next call to report
  void wait_for_upload(bool report) {
    if (!uploading_) return;
    uploading_ = false;
    try {
      cl_checked("uploading a buffer", [&] { return upload_.wait(); });
    } catch (const Error&) {
      if (report) throw;
    }
  }

  Device* dev_ = nullptr;
  cl::Buffer buffer_;
  size_t count_ = 0;
  size_t capacity_ = 0;
  std::vector<T> staging_;  // what the last upload writes from
  cl::Event upload_;        // that write
  bool uploading_ = false;  // whether it may still be in the queue
};

// the wait for reads enqueued by Buffer::enqueue_download: wait() at the end; if an error unwinds
// the stack first, the destructor still waits for the queue, so no read lands in a vector that is
// gone (declare the vectors before this)
class PendingReads {
 public:
  explicit PendingReads(Device& dev) : dev_(dev) {}
  PendingReads(const PendingReads&) = delete;
  PendingReads& operator=(const PendingReads&) = delete;
  ~PendingReads() {
    if (waited_) return;
    try {
      dev_.finish();
    } catch (const Error&) {
      // the error that unwinds the stack is the one to report
    }
  }
  void wait() {
    waited_ = true;
    dev_.finish();
  }

 private:
  Device& dev_;
  bool waited_ = false;
};

// kernel arguments: Buffer<T> binds its cl::Buffer, anything else binds by value
namespace detail {
template <class T>
const cl::Buffer& arg(const Buffer<T>& b) { return b.raw(); }
template <class T>
const T& arg(const T& v) { return v; }
}  // namespace detail

template <class... Args>
void set_args(cl::Kernel& kernel, const Args&... args) {
  cl_uint index = 0;
  cl_checked("setting kernel arguments", [&] {
    (kernel.setArg(index++, detail::arg(args)), ...);
    return 0;
  });
}

// the work-group size of every 1-D launch; results depend on it only where a kernel
// says so (the scan), and a fixed value keeps runs bit-identical across calls
inline constexpr size_t kWorkGroupSize = 64;

// enqueues `kernel` over `count` items (padded to whole work-groups; kernels bound-check)
void launch(Device& dev, cl::Kernel& kernel, size_t count, const char* what);

// enqueues `kernel` as one work-group of `size` work-items (a chain walked by one work-item with
// the group's help: kernels/bucket.cl)
void launch_group(Device& dev, cl::Kernel& kernel, size_t size, const char* what);

// enqueues `kernel` as `groups` work-groups of one work-item each: one walk per group, side by
// side on a CPU device's cores (kernels/solver.cl pgs_runs)
void launch_walks(Device& dev, cl::Kernel& kernel, size_t groups, const char* what);

}  // namespace talus
