// fuzz target: a machine file (vehicle/machine.hpp, parse_machine), then the model built from it
// (WheelLoader checks what only the built model can: body names, cylinder ranges, the bucket)
#include "fuzz/fuzz_target.hpp"
#include "vehicle/machine.hpp"
#include "vehicle/wheel_loader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const auto path =
      talus::fuzz::write_input("machine.json", reinterpret_cast<const char*>(data), size);
  talus::fuzz::expect_contract("fuzz_machine", [&] {
    const talus::vehicle::MachineDescription m = talus::vehicle::parse_machine(path.string());
    talus::vehicle::WheelLoader loader(m);
  });
  return 0;
}
