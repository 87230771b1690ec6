// fuzz target: a pile profile (terrain/pile.hpp, load_pile_profile)
#include "fuzz/fuzz_target.hpp"
#include "terrain/pile.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const auto path =
      talus::fuzz::write_input("pile.json", reinterpret_cast<const char*>(data), size);
  talus::fuzz::expect_contract("fuzz_pile", [&] { talus::load_pile_profile(path.string()); });
  return 0;
}
