#include "digging/saved_state.hpp"

#include <algorithm>
#include <array>
#include <sstream>
#include <string_view>
#include <utility>
#include <vector>

#include "host/binary.hpp"
#include "host/error.hpp"

namespace talus {

namespace {

// the file's first bytes: what it is, before its version
constexpr std::array<char, 8> kMagic = {'T', 'A', 'L', 'U', 'S', 'S', 'T', 'A'};
// what a user does about a state file that cannot be read
constexpr const char* kStateFileHint = "truncated or not a talus state file; save it again";

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

}  // namespace

std::string seal_state(const SavedStateHeader& header, const std::string& payload) {
  ByteWriter w;
  for (const char c : kMagic) w.u8(static_cast<std::uint8_t>(c));
  w.u32(kStateFormatVersion);
  w.str(header.key);
  w.str(header.commit);
  w.str(header.device);
  w.str(payload);
  w.u64(fnv1a64(w.bytes()));
  return std::move(w.bytes());
}

SavedStateHeader open_state(const std::string& bytes, const std::string& where,
                            std::string* payload) {
  // the magic and version first: a file of another kind or version is named as such
  if (bytes.size() < kMagic.size() ||
      bytes.compare(0, kMagic.size(), kMagic.data(), kMagic.size()) != 0)
    throw InputError(where +
                     ": not a talus state file (no 'TALUSSTA' at its start); give a file "
                     "that Simulation::save_state wrote");
  ByteReader head(bytes, bytes.size(), where, kStateFileHint);
  for (std::size_t k = 0; k < kMagic.size(); ++k) head.u8("magic");
  const std::uint32_t version = head.u32("format version");
  if (version != kStateFormatVersion)
    throw InputError(where + ": state format version " + std::to_string(version) +
                     ", this talus reads " + std::to_string(kStateFormatVersion) +
                     "; save the state again with this talus");
  // then the checksum over everything before it
  if (bytes.size() < kMagic.size() + 4 + 8)
    throw InputError(where + ": the file ends inside its checksum (" + kStateFileHint + ")");
  const std::size_t body = bytes.size() - 8;
  ByteReader tail(std::string_view(bytes).substr(body), 8, where, kStateFileHint);
  if (tail.u64("checksum") != fnv1a64(std::string_view(bytes).substr(0, body)))
    throw InputError(where + ": the checksum does not match (" + kStateFileHint + ")");
  ByteReader r(bytes, body, where, kStateFileHint);
  for (std::size_t k = 0; k < kMagic.size(); ++k) r.u8("magic");
  r.u32("format version");
  SavedStateHeader header;
  header.key = r.str("key");
  header.commit = r.str("commit");
  header.device = r.str("device");
  std::string content = r.str("payload");
  if (r.left() != 0)
    throw InputError(where + ": " + std::to_string(r.left()) + " bytes after the payload (" +
                     kStateFileHint + ")");
  if (payload) *payload = std::move(content);
  return header;
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
