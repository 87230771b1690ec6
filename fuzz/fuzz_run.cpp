// fuzz target: a measured run (sim2real/timeseries.hpp, load_run): the folder's summary.json and
// timeseries.csv from one input, split at its first line "--- timeseries.csv ---" (the corpus
// files are written so; an input without the line is all summary, with an empty series)
#include <cstring>

#include "fuzz/fuzz_target.hpp"
#include "sim2real/timeseries.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  static const char kSeparator[] = "\n--- timeseries.csv ---\n";
  const std::string input(reinterpret_cast<const char*>(data), size);
  const std::size_t split = input.find(kSeparator);
  const std::string summary = input.substr(0, split);
  const std::string series =
      split == std::string::npos ? std::string() : input.substr(split + std::strlen(kSeparator));
  talus::fuzz::write_input("summary.json", summary.data(), summary.size());
  talus::fuzz::write_input("timeseries.csv", series.data(), series.size());
  talus::fuzz::expect_contract("fuzz_run",
                               [&] { talus::sim2real::load_run(talus::fuzz::scratch()); });
  return 0;
}
