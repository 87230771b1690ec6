#include "io/vtk.hpp"

#include <cstring>

namespace talus {

// the bytes are written in the machine's order and declared little-endian
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "VTK output is written as little-endian bytes");

std::string VtkAppendedData::element(const std::string& type, const std::string& name,
                                     int components, const void* data, std::uint64_t size) {
  // the element points at the byte count that precedes this array's bytes in the block
  std::string e = "<DataArray type=\"" + type + "\" Name=\"" + name + "\"";
  if (components != 1) e += " NumberOfComponents=\"" + std::to_string(components) + "\"";
  e += " format=\"appended\" offset=\"" + std::to_string(bytes_.size()) + "\"/>\n";
  bytes_.append(reinterpret_cast<const char*>(&size), sizeof(size));
  bytes_.append(static_cast<const char*>(data), size);
  return e;
}

std::string VtkAppendedData::float32(const std::string& name, const std::vector<double>& values,
                                     int components) {
  const std::vector<float> f(values.begin(), values.end());
  return element("Float32", name, components, f.data(), f.size() * sizeof(float));
}

std::string VtkAppendedData::int64(const std::string& name,
                                   const std::vector<std::int64_t>& values) {
  return element("Int64", name, 1, values.data(), values.size() * sizeof(std::int64_t));
}

std::string VtkAppendedData::uint8(const std::string& name,
                                   const std::vector<std::uint8_t>& values) {
  return element("UInt8", name, 1, values.data(), values.size());
}

std::string vtk_file_open(const std::string& type) {
  return "<?xml version=\"1.0\"?>\n<VTKFile type=\"" + type +
         "\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n";
}

std::string vtk_file_close(const VtkAppendedData& appended) {
  // the block starts after the underscore; whitespace before it is not part of the data
  return "<AppendedData encoding=\"raw\">\n_" + appended.bytes() +
         "\n</AppendedData>\n</VTKFile>\n";
}

}  // namespace talus
