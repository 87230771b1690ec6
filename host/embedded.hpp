// Kernel sources embedded into the library at build time (cmake/embed_kernels.cmake).
#pragma once
#include <string>
#include <vector>

namespace talus {

struct EmbeddedSource {
  const char* name;    // file name inside kernels/, e.g. "broadphase.cl"
  std::string text;    // the file's contents
};

// the generated table, sorted by name
const std::vector<EmbeddedSource>& embedded_sources();

// one file's text; throws talus::Error naming the file when it is not embedded
const std::string& embedded_source(const std::string& name);

}  // namespace talus
