// Owning handles for Embree 3 objects (device, scene, geometry) and error checking that turns
// Embree's error codes into talus::Error naming the failed call. Used by solvers/bucket_contacts
// (closest-point queries on the bucket mesh) and terrain/heightmap (rays on the terrain surface).
//
// Embree reports errors through rtcGetDeviceError and an optional callback; the callback here only
// records the message (it must not throw through Embree's C frames), and `check` reads the code
// after each call and throws.
#pragma once
#include <embree3/rtcore.h>

#include <memory>
#include <string>

namespace talus::embree {

// the symbolic name of an Embree error code, e.g. "RTC_ERROR_INVALID_ARGUMENT"
const char* error_name(RTCError code);

// an Embree device; copies share it (Embree reference counting)
class Device {
 public:
  // `config` is Embree's device configuration string (e.g. "threads=1"); throws talus::Error
  explicit Device(const char* config = "verbose=0");
  Device(const Device& o);
  Device& operator=(const Device& o);
  Device(Device&& o) noexcept;
  Device& operator=(Device&& o) noexcept;
  ~Device();

  RTCDevice get() const { return device_; }
  // throws talus::Error("embree <call>: <code>: <message>") when the device has a pending error
  void check(const char* call) const;

 private:
  // the last message of the error callback; on the heap so the pointer Embree holds survives moves
  struct Log {
    std::string message;
  };
  RTCDevice device_ = nullptr;
  std::shared_ptr<Log> log_;
};

// a committed-or-not scene; holds its device alive
class Scene {
 public:
  // flags: RTC_SCENE_FLAG_ROBUST for watertight ray queries; throws talus::Error
  explicit Scene(const Device& device, RTCSceneFlags flags = RTC_SCENE_FLAG_NONE);
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;
  Scene(Scene&& o) noexcept;
  Scene& operator=(Scene&& o) noexcept;
  ~Scene();

  RTCScene get() const { return scene_; }
  const Device& device() const { return device_; }
  void commit();

 private:
  Device device_;
  RTCScene scene_ = nullptr;
};

// a triangle mesh geometry with float vertices (x, y, z per vertex, 16-byte padded as Embree
// requires) and unsigned index triples, attached to `scene` under the returned geometry id.
// Embree only sees float copies; callers keep their double data for exact arithmetic.
unsigned attach_triangles(Scene& scene, const float* xyz, size_t vertex_count, const unsigned* indices,
                          size_t triangle_count);

}  // namespace talus::embree
