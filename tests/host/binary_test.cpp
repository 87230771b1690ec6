// The byte writer and reader of talus's binary files (host/binary.hpp): numbers come back bit for
// bit, the bytes are little-endian whatever the machine, and a short or mislabelled file is one
// InputError naming the file and what it ended inside.
#include "host/binary.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "host/error.hpp"

namespace talus {
namespace {

// a number's bit pattern: NaN payloads and signed zeros compare as what they are
std::uint64_t bits(double d) {
  std::uint64_t b = 0;
  std::memcpy(&b, &d, sizeof b);
  return b;
}
std::uint32_t bits(float f) {
  std::uint32_t b = 0;
  std::memcpy(&b, &f, sizeof b);
  return b;
}

ByteReader reader(const std::string& bytes) {
  return ByteReader(bytes, bytes.size(), "f.bin", "save it again");
}

TEST(Binary, NumbersComeBackBitForBit) {
  std::mt19937_64 rng(std::random_device{}());
  std::uniform_real_distribution<double> u(-1e6, 1e6);
  const std::vector<double> specials = {0.0,
                                        -0.0,
                                        std::numeric_limits<double>::denorm_min(),
                                        std::numeric_limits<double>::infinity(),
                                        std::numeric_limits<double>::quiet_NaN(),
                                        u(rng),
                                        u(rng)};
  ByteWriter w;
  for (const double d : specials) w.f64(d);
  const float f = static_cast<float>(u(rng));
  w.f32(f);
  w.u8(200);
  w.u32(0xdeadbeefu);
  w.i64(-42);
  w.str(std::string("a\0b", 3));
  w.tag("section");
  ByteReader r = reader(w.bytes());
  for (const double d : specials) {
    EXPECT_EQ(bits(r.f64("numbers")), bits(d)) << d;
  }
  EXPECT_EQ(bits(r.f32("float")), bits(f));
  EXPECT_EQ(r.u8("byte"), 200);
  EXPECT_EQ(r.u32("word"), 0xdeadbeefu);
  EXPECT_EQ(r.i64("signed"), -42);
  EXPECT_EQ(r.str("string"), std::string("a\0b", 3));
  r.expect("section");
  EXPECT_EQ(r.left(), 0u);
}

// the file's order is little-endian: the low byte first
TEST(Binary, LittleEndianOnDisk) {
  ByteWriter w;
  w.u32(0x04030201u);
  w.u64(0x0807060504030201ULL);
  EXPECT_EQ(w.bytes(), std::string("\x01\x02\x03\x04\x01\x02\x03\x04\x05\x06\x07\x08", 12));
}

// device structs of 4-byte fields: each word little-endian, the struct back bit for bit
TEST(Binary, DeviceWordsComeBack) {
  struct Pair {
    float x;
    int i;
  };
  const std::vector<Pair> v = {{1.5f, -3}, {-0.0f, 7}};
  ByteWriter w;
  write_words(w, v);
  ByteReader r = reader(w.bytes());
  const std::vector<Pair> back = read_words<Pair>(r, "pairs");
  ASSERT_EQ(back.size(), v.size());
  EXPECT_EQ(std::memcmp(back.data(), v.data(), sizeof(Pair) * v.size()), 0);
}

// a short file names itself and what it ended inside; a count larger than the file is refused
// before anything is allocated
TEST(Binary, ShortFilesAreNamed) {
  ByteWriter w;
  w.u64(1ULL << 60);  // a length the file does not hold
  ByteReader r = reader(w.bytes());
  try {
    (void)read_words<int>(r, "contacts");
    ADD_FAILURE() << "read past the end";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "f.bin: the file ends inside its contacts (save it again)");
  }
  ByteReader empty = reader("");
  EXPECT_THROW((void)empty.f64("clock"), InputError);
}

TEST(Binary, AnotherSectionIsNamed) {
  ByteWriter w;
  w.tag("machine");
  ByteReader r = reader(w.bytes());
  try {
    r.expect("particles");
    ADD_FAILURE() << "accepted another section";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("expected the section 'particles', found 'machine'"),
              std::string::npos)
        << e.what();
  }
}

// FNV-1a's published test values (Fowler, Noll, Vo)
TEST(Binary, Fnv1a64KnownValues) {
  EXPECT_EQ(fnv1a64(""), 0xcbf29ce484222325ULL);
  EXPECT_EQ(fnv1a64("a"), 0xaf63dc4c8601ec8cULL);
  EXPECT_EQ(fnv1a64("foobar"), 0x85944171f73967e8ULL);
}

}  // namespace
}  // namespace talus
