// The envelope of a saved state (digging/saved_state.hpp): a payload sealed and opened comes back
// with its key, commit and device; another kind of file, another version, a cut or a flipped byte
// is one InputError naming the file; two keys are compared line by line.
#include "digging/saved_state.hpp"

#include <gtest/gtest.h>

#include <string>

#include "host/error.hpp"

namespace talus {
namespace {

SavedStateHeader header() {
  SavedStateHeader h;
  h.key = "scenario=HD27 hd27.json 1234\nlevel=D400\nseed=1\n";
  h.commit = "abc123";
  h.device = "Portable Computing Language / cpu";
  return h;
}

TEST(SavedStateFile, SealedPayloadOpensAgain) {
  const std::string payload("\x00\x01state\xff", 8);
  const std::string bytes = seal_state(header(), payload);
  EXPECT_EQ(bytes.substr(0, 8), "TALUSSTA");
  std::string back;
  const SavedStateHeader h = open_state(bytes, "s.state", &back);
  EXPECT_EQ(back, payload);
  EXPECT_EQ(h.key, header().key);
  EXPECT_EQ(h.commit, "abc123");
  EXPECT_EQ(h.device, header().device);
}

TEST(SavedStateFile, DamagedFilesAreRefusedByName) {
  const std::string bytes = seal_state(header(), "payload");
  const auto refused = [](const std::string& b, const std::string& says) {
    try {
      (void)open_state(b, "s.state", nullptr);
      ADD_FAILURE() << "opened a damaged file; expected " << says;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("s.state: ", 0), 0u) << what;
      EXPECT_NE(what.find(says), std::string::npos) << what;
    }
  };
  refused("TALUSPIL", "not a talus state file");
  refused("", "not a talus state file");
  refused(bytes.substr(0, 10), "ends inside");
  refused(bytes.substr(0, bytes.size() - 1), "checksum");
  // every byte after the magic and version matters
  for (std::size_t k = 12; k < bytes.size(); ++k) {
    std::string flipped = bytes;
    flipped[k] ^= 0x01;
    EXPECT_THROW((void)open_state(flipped, "s.state", nullptr), InputError) << "byte " << k;
  }
  std::string version = bytes;
  version[8] = static_cast<char>(kStateFormatVersion + 1);
  refused(version, "state format version " + std::to_string(kStateFormatVersion + 1) +
                       ", this talus reads " + std::to_string(kStateFormatVersion));
}

TEST(SavedStateFile, KeyDifferenceNamesTheFirstLine) {
  EXPECT_EQ(key_difference("a=1\nb=2\n", "a=1\nb=2\n"), "");
  EXPECT_EQ(key_difference("a=1\nb=2\n", "a=1\nb=3\n"),
            "b=2 (saved) against b=3 (this simulation)");
  EXPECT_EQ(key_difference("a=1\n", "a=1\nb=3\n"),
            "(nothing) (saved) against b=3 (this simulation)");
}

}  // namespace
}  // namespace talus
