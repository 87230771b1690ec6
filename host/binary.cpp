#include "host/binary.hpp"

#include <cstdio>
#include <cstring>
#include <utility>

#include "host/error.hpp"

namespace talus {

namespace {
// FNV-1a's 64-bit parameters (Fowler, Noll, Vo; http://www.isthe.com/chongo/tech/comp/fnv/)
constexpr std::uint64_t kFnvOffset = 14695981039346656037ULL;
constexpr std::uint64_t kFnvPrime = 1099511628211ULL;
}  // namespace

std::uint64_t fnv1a64(std::string_view bytes) {
  std::uint64_t h = kFnvOffset;
  for (const char c : bytes) {
    h ^= static_cast<std::uint8_t>(c);
    h *= kFnvPrime;
  }
  return h;
}

std::string key_file_name(std::string_view key) {
  char name[17];
  std::snprintf(name, sizeof name, "%016llx", static_cast<unsigned long long>(fnv1a64(key)));
  return name;
}

void begin_sealed(ByteWriter& w, const SealedFormat& format) {
  for (const char c : format.magic) w.u8(static_cast<std::uint8_t>(c));
  w.u32(format.version);
}

void end_sealed(ByteWriter& w) { w.u64(fnv1a64(w.bytes())); }

ByteReader open_sealed(const std::string& bytes, const SealedFormat& format,
                       const std::string& where) {
  const std::string hint = "truncated or not a talus " + format.kind + " file; " + format.fix;
  const std::size_t head = format.magic.size() + 4;
  // the magic first: a file of another kind is named as such, not as corrupt
  if (bytes.size() < format.magic.size() ||
      bytes.compare(0, format.magic.size(), format.magic) != 0)
    throw InputError(where + ": not a talus " + format.kind + " file (no '" + format.magic +
                     "' at its start); " + format.fix);
  ByteReader version(std::string_view(bytes).substr(format.magic.size()),
                     bytes.size() - format.magic.size(), where, hint);
  const std::uint32_t v = version.u32("format version");
  if (v != format.version)
    throw InputError(where + ": " + format.kind + " format version " + std::to_string(v) +
                     ", this talus reads " + std::to_string(format.version) + "; " + format.fix);
  // then the checksum over everything before it
  if (bytes.size() < head + 8)
    throw InputError(where + ": the file ends inside its checksum (" + hint + ")");
  const std::size_t body = bytes.size() - 8;
  ByteReader tail(std::string_view(bytes).substr(body), 8, where, hint);
  if (tail.u64("checksum") != fnv1a64(std::string_view(bytes).substr(0, body)))
    throw InputError(where + ": the checksum does not match (" + hint + ")");
  ByteReader r(bytes, body, where, hint);
  for (std::size_t k = 0; k < head; ++k) r.u8("header");
  return r;
}

void ByteWriter::u32(std::uint32_t v) {
  for (int b = 0; b < 4; ++b) u8(static_cast<std::uint8_t>(v >> (8 * b)));
}

void ByteWriter::u64(std::uint64_t v) {
  for (int b = 0; b < 8; ++b) u8(static_cast<std::uint8_t>(v >> (8 * b)));
}

void ByteWriter::f32(float v) {
  std::uint32_t bits = 0;
  std::memcpy(&bits, &v, sizeof bits);
  u32(bits);
}

void ByteWriter::f64(double v) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &v, sizeof bits);
  u64(bits);
}

void ByteWriter::str(const std::string& s) {
  u64(s.size());
  out_ += s;
}

void ByteWriter::f64s(const double* v, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) f64(v[i]);
}

void ByteWriter::words(const void* data, std::size_t bytes) {
  // each 4-byte field as a number, so the file's order is little-endian on any machine
  const char* p = static_cast<const char*>(data);
  for (std::size_t k = 0; k + 4 <= bytes; k += 4) {
    std::uint32_t word = 0;
    std::memcpy(&word, p + k, 4);
    u32(word);
  }
}

ByteReader::ByteReader(std::string_view bytes, std::size_t end, std::string where, std::string hint)
    : bytes_(bytes), end_(end), where_(std::move(where)), hint_(std::move(hint)) {}

void ByteReader::need(std::uint64_t n, const char* what) const {
  if (n > end_ - pos_)
    throw InputError(where_ + ": the file ends inside its " + what + " (" + hint_ + ")");
}

void ByteReader::need_elements(std::uint64_t count, std::uint64_t size, const char* what) const {
  // count * size may overflow: compare by division
  if (size > 0 && count > left() / size)
    throw InputError(where_ + ": the file ends inside its " + what + " (" + hint_ + ")");
}

std::uint8_t ByteReader::u8(const char* what) {
  need(1, what);
  return static_cast<std::uint8_t>(bytes_[pos_++]);
}

std::uint32_t ByteReader::u32(const char* what) {
  need(4, what);
  std::uint32_t v = 0;
  for (int b = 0; b < 4; ++b)
    v |= static_cast<std::uint32_t>(static_cast<std::uint8_t>(bytes_[pos_++])) << (8 * b);
  return v;
}

std::uint64_t ByteReader::u64(const char* what) {
  need(8, what);
  std::uint64_t v = 0;
  for (int b = 0; b < 8; ++b)
    v |= static_cast<std::uint64_t>(static_cast<std::uint8_t>(bytes_[pos_++])) << (8 * b);
  return v;
}

float ByteReader::f32(const char* what) {
  const std::uint32_t bits = u32(what);
  float v = 0.0f;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

double ByteReader::f64(const char* what) {
  const std::uint64_t bits = u64(what);
  double v = 0.0;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

std::string ByteReader::str(const char* what) {
  const std::uint64_t n = u64(what);
  need(n, what);
  std::string s(bytes_.substr(pos_, n));
  pos_ += n;
  return s;
}

void ByteReader::f64s(double* v, std::size_t n, const char* what) {
  need_elements(n, 8, what);
  for (std::size_t i = 0; i < n; ++i) v[i] = f64(what);
}

void ByteReader::expect(const std::string& name) {
  const std::string found = str(name.c_str());
  if (found != name)
    throw InputError(where_ + ": expected the section '" + name + "', found '" +
                     found.substr(0, 40) + "' (" + hint_ + ")");
}

void ByteReader::words(void* data, std::size_t bytes, const char* what) {
  need(bytes, what);
  char* p = static_cast<char*>(data);
  for (std::size_t k = 0; k + 4 <= bytes; k += 4) {
    const std::uint32_t word = u32(what);
    std::memcpy(p + k, &word, 4);
  }
}

}  // namespace talus
