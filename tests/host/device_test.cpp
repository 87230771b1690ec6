// host/device: device discovery, program builds from embedded sources, error reporting.
#include <gtest/gtest.h>

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

TEST(Device, MissingKernelFileIsNamed) {
  try {
    embedded_source("does_not_exist.cl");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("does_not_exist.cl"), std::string::npos);
  }
}

}  // namespace
}  // namespace talus
