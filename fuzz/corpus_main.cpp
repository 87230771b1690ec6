// Replays saved fuzzing inputs through a fuzz target without libFuzzer (ctest fuzz.*): every file
// under the folders given, in name order, through LLVMFuzzerTestOneInput. A finding aborts, so
// the test fails naming the file last printed.
//
// usage: fuzz_TARGET_corpus DIR...
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size);

int main(int argc, char** argv) {
  std::vector<std::filesystem::path> files;
  for (int a = 1; a < argc; ++a) {
    std::error_code ec;
    for (const auto& e : std::filesystem::recursive_directory_iterator(argv[a], ec))
      if (e.is_regular_file()) files.push_back(e.path());
    if (ec) {
      std::fprintf(stderr, "%s: cannot read the corpus folder %s: %s\n", argv[0], argv[a],
                   ec.message().c_str());
      return 2;
    }
  }
  if (files.empty()) {
    std::fprintf(stderr, "%s: no inputs under the folders given\n", argv[0]);
    return 2;
  }
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::fprintf(stderr, "%s\n", f.string().c_str());
    LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
  }
  std::printf("%zu inputs replayed, none broke the loader's contract\n", files.size());
  return 0;
}
