// fuzz target: a scenario file (vehicle/scenario.hpp, load_scenario)
#include "fuzz/fuzz_target.hpp"
#include "vehicle/scenario.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const auto path =
      talus::fuzz::write_input("scenario.json", reinterpret_cast<const char*>(data), size);
  talus::fuzz::expect_contract("fuzz_scenario",
                               [&] { talus::vehicle::load_scenario(path.string()); });
  return 0;
}
