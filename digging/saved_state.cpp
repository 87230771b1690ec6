#include "digging/saved_state.hpp"

#include <algorithm>
#include <sstream>
#include <string_view>
#include <utility>
#include <vector>

#include "host/binary.hpp"
#include "host/error.hpp"

namespace talus {

namespace {

// the file's magic, version and what a user does about a bad one
const SealedFormat& state_format() {
  static const SealedFormat format{"TALUSSTA", kStateFormatVersion, "state",
                                   "save the state again with this talus"};
  return format;
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

}  // namespace

std::string seal_state(const SavedStateHeader& header, const std::string& payload) {
  ByteWriter w;
  begin_sealed(w, state_format());
  w.str(header.key);
  w.str(header.commit);
  w.str(header.device);
  w.str(payload);
  end_sealed(w);
  return std::move(w.bytes());
}

SavedStateHeader open_state(const std::string& bytes, const std::string& where,
                            std::string* payload) {
  // magic, version and checksum checked before anything is read
  ByteReader r = open_sealed(bytes, state_format(), where);
  SavedStateHeader header;
  header.key = r.str("key");
  header.commit = r.str("commit");
  header.device = r.str("device");
  std::string content = r.str("payload");
  if (r.left() != 0)
    throw InputError(where + ": " + std::to_string(r.left()) + " bytes after the payload (" +
                     r.hint() + ")");
  if (payload) *payload = std::move(content);
  return header;
}

ByteReader payload_reader(const std::string& payload, const std::string& where) {
  return ByteReader(payload, payload.size(), where,
                    "truncated or not a talus state file; " + state_format().fix);
}

std::string key_difference(const std::string& saved, const std::string& mine) {
  const std::vector<std::string> a = lines(saved), b = lines(mine);
  for (std::size_t k = 0; k < std::max(a.size(), b.size()); ++k) {
    const std::string x = k < a.size() ? a[k] : "(nothing)";
    const std::string y = k < b.size() ? b[k] : "(nothing)";
    if (x != y) return x + " (saved) against " + y + " (this simulation)";
  }
  return {};
}

}  // namespace talus
