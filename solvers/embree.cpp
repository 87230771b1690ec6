#include "solvers/embree.hpp"

#include <algorithm>
#include <cstring>
#include <utility>

#include "host/error.hpp"

namespace talus::embree {

namespace {

// records Embree's message; the code itself stays readable through rtcGetDeviceError
void record_error(void* user, RTCError code, const char* str) {
  if (code == RTC_ERROR_NONE || user == nullptr) return;
  static_cast<std::string*>(user)->assign(str ? str : "");
}

struct GeometryRelease {
  void operator()(RTCGeometry g) const { rtcReleaseGeometry(g); }
};
using GeometryHandle = std::unique_ptr<RTCGeometryTy, GeometryRelease>;

}  // namespace

const char* error_name(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE: return "RTC_ERROR_NONE";
    case RTC_ERROR_UNKNOWN: return "RTC_ERROR_UNKNOWN";
    case RTC_ERROR_INVALID_ARGUMENT: return "RTC_ERROR_INVALID_ARGUMENT";
    case RTC_ERROR_INVALID_OPERATION: return "RTC_ERROR_INVALID_OPERATION";
    case RTC_ERROR_OUT_OF_MEMORY: return "RTC_ERROR_OUT_OF_MEMORY";
    case RTC_ERROR_UNSUPPORTED_CPU: return "RTC_ERROR_UNSUPPORTED_CPU";
    case RTC_ERROR_CANCELLED: return "RTC_ERROR_CANCELLED";
  }
  return "RTC_ERROR_(unrecognised)";
}

Device::Device(const char* config) : log_(std::make_shared<Log>()) {
  device_ = rtcNewDevice(config);
  if (device_ == nullptr) {
    // without a device the error is kept per thread and read with a null handle
    throw Error(std::string("embree rtcNewDevice: ") + error_name(rtcGetDeviceError(nullptr)) +
                " (config \"" + (config ? config : "") + "\"; is the CPU supported by this Embree build?)");
  }
  rtcSetDeviceErrorFunction(device_, record_error, &log_->message);
}

Device::Device(const Device& o) : device_(o.device_), log_(o.log_) {
  if (device_) rtcRetainDevice(device_);
}

Device& Device::operator=(const Device& o) {
  if (this != &o) {
    Device copy(o);
    *this = std::move(copy);
  }
  return *this;
}

Device::Device(Device&& o) noexcept
    : device_(std::exchange(o.device_, nullptr)), log_(std::move(o.log_)) {}

Device& Device::operator=(Device&& o) noexcept {
  if (this != &o) {
    if (device_) rtcReleaseDevice(device_);
    device_ = std::exchange(o.device_, nullptr);
    log_ = std::move(o.log_);
  }
  return *this;
}

Device::~Device() {
  if (device_) rtcReleaseDevice(device_);
}

void Device::check(const char* call) const {
  const RTCError code = rtcGetDeviceError(device_);
  if (code == RTC_ERROR_NONE) return;
  std::string msg = std::string("embree ") + call + ": " + error_name(code);
  if (log_ && !log_->message.empty()) {
    msg += ": " + log_->message;
    log_->message.clear();
  }
  throw Error(msg);
}

Scene::Scene(const Device& device, RTCSceneFlags flags) : device_(device) {
  scene_ = rtcNewScene(device_.get());
  if (scene_ == nullptr) device_.check("rtcNewScene");
  if (scene_ == nullptr) throw Error("embree rtcNewScene: returned no scene");
  rtcSetSceneFlags(scene_, flags);
  device_.check("rtcSetSceneFlags");
}

Scene::Scene(Scene&& o) noexcept : device_(o.device_), scene_(std::exchange(o.scene_, nullptr)) {}

Scene& Scene::operator=(Scene&& o) noexcept {
  if (this != &o) {
    if (scene_) rtcReleaseScene(scene_);
    scene_ = std::exchange(o.scene_, nullptr);
    device_ = o.device_;
  }
  return *this;
}

Scene::~Scene() {
  if (scene_) rtcReleaseScene(scene_);
}

void Scene::commit() {
  rtcCommitScene(scene_);
  device_.check("rtcCommitScene");
}

unsigned attach_triangles(Scene& scene, const float* xyz, size_t vertex_count, const unsigned* indices,
                          size_t triangle_count) {
  const Device& dev = scene.device();
  GeometryHandle geom(rtcNewGeometry(dev.get(), RTC_GEOMETRY_TYPE_TRIANGLE));
  if (!geom) dev.check("rtcNewGeometry");
  if (!geom) throw Error("embree rtcNewGeometry: returned no geometry");
  // embree allocates the buffers (with the padding its SIMD loads need); we copy into them
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom.get(), RTC_BUFFER_TYPE_VERTEX, 0,
                                                        RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertex_count));
  dev.check("rtcSetNewGeometryBuffer(vertex)");
  std::memcpy(v, xyz, 3 * sizeof(float) * vertex_count);
  auto* t = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom.get(), RTC_BUFFER_TYPE_INDEX, 0,
                                                           RTC_FORMAT_UINT3, 3 * sizeof(unsigned), triangle_count));
  dev.check("rtcSetNewGeometryBuffer(index)");
  std::memcpy(t, indices, 3 * sizeof(unsigned) * triangle_count);
  rtcCommitGeometry(geom.get());
  dev.check("rtcCommitGeometry");
  // the scene retains the geometry; our handle is released on return
  const unsigned id = rtcAttachGeometry(scene.get(), geom.get());
  dev.check("rtcAttachGeometry");
  return id;
}

}  // namespace talus::embree
