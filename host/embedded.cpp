#include "host/embedded.hpp"

#include "host/error.hpp"

namespace talus {

const std::string& embedded_source(const std::string& name) {
  for (auto& e : embedded_sources())
    if (name == e.name) return e.text;
  throw Error("kernel source '" + name + "' is not embedded: add kernels/" + name +
              " and re-run cmake so cmake/embed_kernels.cmake picks it up");
}

}  // namespace talus
