// Binary files that talus writes and reads back bit for bit: the settled piles of the pile cache
// (terrain/pile_cache) and the saved simulation states (digging/saved_state, issue 16).
//
// Design: every number is written little-endian whatever the machine's order, one element at a
// time, so a file moves between machines; doubles and floats go bit for bit (NaN payloads and
// signed zeros included), which is what makes a state read back continue bit-identically. A
// reader checks every length before it reads or allocates, so a short or hostile file is named
// with what it ended inside, never read past its end. What a file means (its magic, version and
// sections) is its writer's; this module only moves the bytes.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace talus {

// FNV-1a, 64 bits (Fowler, Noll, Vo; offset basis 14695981039346656037, prime 1099511628211):
// the checksum of the files and the name of a pile's key. Not cryptographic: a file also holds
// what it is checked against, so a collision is a miss, never a wrong answer
std::uint64_t fnv1a64(std::string_view bytes);
// a cache file's name for a key: its FNV-1a 64 as 16 hex digits (the pile cache's piles, the
// program binaries)
std::string key_file_name(std::string_view key);

// appends little-endian numbers to a byte string
class ByteWriter {
 public:
  void u8(std::uint8_t v) { out_.push_back(static_cast<char>(v)); }
  void u32(std::uint32_t v);
  void u64(std::uint64_t v);
  void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
  void f32(float v);
  void f64(double v);
  // a length, then the bytes
  void str(const std::string& s);
  // n doubles (a vector's or matrix's coefficients, in its storage order)
  void f64s(const double* v, std::size_t n);
  // a section's name, which the reader expects back (ByteReader::expect), so a file written by
  // another layout is named as such instead of read as numbers
  void tag(const std::string& name) { str(name); }
  // a device struct made only of 4-byte fields (floats and ints, as the OpenCL layouts in
  // kernels/ are): its words, each little-endian
  void words(const void* data, std::size_t bytes);
  const std::string& bytes() const { return out_; }
  std::string& bytes() { return out_; }

 private:
  std::string out_;
};

// reads the same numbers back from [0, end) of a byte string. Every read names what it reads
// (`what`); a read past `end` throws InputError "<where>: the file ends inside its <what>
// (<hint>)", where `hint` says what the user can do about it
class ByteReader {
 public:
  ByteReader(std::string_view bytes, std::size_t end, std::string where, std::string hint);
  // InputError unless n more bytes are there
  void need(std::uint64_t n, const char* what) const;
  // InputError unless `count` elements of `size` bytes each are there (checked before a caller
  // allocates them, without overflow)
  void need_elements(std::uint64_t count, std::uint64_t size, const char* what) const;
  std::uint8_t u8(const char* what);
  std::uint32_t u32(const char* what);
  std::uint64_t u64(const char* what);
  std::int64_t i64(const char* what) { return static_cast<std::int64_t>(u64(what)); }
  float f32(const char* what);
  double f64(const char* what);
  std::string str(const char* what);
  void f64s(double* v, std::size_t n, const char* what);
  // reads a section's name (ByteWriter::tag); InputError naming both when it is another
  void expect(const std::string& name);
  void words(void* data, std::size_t bytes, const char* what);
  std::size_t left() const { return end_ - pos_; }
  std::size_t position() const { return pos_; }
  const std::string& where() const { return where_; }
  const std::string& hint() const { return hint_; }

 private:
  std::string_view bytes_;
  std::size_t end_;
  std::size_t pos_ = 0;
  std::string where_, hint_;
};

// talus's sealed files (the pile cache's piles, the saved states): an 8-byte magic, a u32
// format version, the body, then the FNV-1a 64 of every byte before it
struct SealedFormat {
  std::string magic;      // 8 characters: what the file is ("TALUSPIL")
  std::uint32_t version;  // the version this talus reads and writes
  std::string kind;       // in messages: "pile", "state"
  std::string fix;  // what the user does about a bad file: "delete it, the pile is built again"
};
// starts a sealed file: the magic and the version
void begin_sealed(ByteWriter& w, const SealedFormat& format);
// ends it: the checksum of every byte written so far
void end_sealed(ByteWriter& w);
// a reader over a sealed file's body (after the magic and version, before the checksum), once
// the magic, the version and the checksum are checked, in that order, so that a file of another
// kind or version is named as such rather than as corrupt; InputError naming `where`, the defect
// and format.fix. The reader names a short body the same way
ByteReader open_sealed(const std::string& bytes, const SealedFormat& format,
                       const std::string& where);

// a vector of 4-byte-field device structs (cl_float4, TlContact, ...): its length, then its words
template <class T>
void write_words(ByteWriter& w, const std::vector<T>& v) {
  static_assert(sizeof(T) % 4 == 0, "a device struct of 4-byte fields");
  w.u64(v.size());
  if (!v.empty()) w.words(v.data(), v.size() * sizeof(T));
}
template <class T>
std::vector<T> read_words(ByteReader& r, const char* what) {
  static_assert(sizeof(T) % 4 == 0, "a device struct of 4-byte fields");
  const std::uint64_t n = r.u64(what);
  r.need_elements(n, sizeof(T), what);
  std::vector<T> v(n);
  if (n > 0) r.words(v.data(), v.size() * sizeof(T), what);
  return v;
}

// a dense matrix or vector of doubles with data() and size() (Eigen's fixed-size types; a
// quaternion through its coeffs()), its coefficients in storage order
template <class M>
void write_matrix(ByteWriter& w, const M& m) {
  w.f64s(m.data(), static_cast<std::size_t>(m.size()));
}
template <class M>
void read_matrix(ByteReader& r, M& m, const char* what) {
  r.f64s(m.data(), static_cast<std::size_t>(m.size()), what);
}

}  // namespace talus
