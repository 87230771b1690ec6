// VTK XML files for ParaView with their arrays in binary: one AppendedData block of raw
// little-endian bytes after the XML, each array preceded by its byte count (UInt64, the file's
// header_type). A float is 4 bytes instead of about 10 characters of ASCII, and readers map it
// without parsing, which is what large runs need (a D50 snapshot holds 450,000 particles).
//
// Use: open the file with vtk_file_open(type), write the XML with every DataArray element made by
// a VtkAppendedData (it queues the bytes and returns the element, whose offset points into the
// block), then close with vtk_file_close(appended). Values are doubles in talus and stored as
// Float32 (positions to 0.1 mm over 1 km, what a picture needs) unless stated otherwise.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace talus {

class VtkAppendedData {
 public:
  // a Float32 DataArray of `components` values per tuple, from doubles
  std::string float32(const std::string& name, const std::vector<double>& values,
                      int components = 1);
  // an Int64 DataArray (cell connectivity and offsets) and a UInt8 one (flags, part ids)
  std::string int64(const std::string& name, const std::vector<std::int64_t>& values);
  std::string uint8(const std::string& name, const std::vector<std::uint8_t>& values);
  // the queued arrays' bytes, each preceded by its UInt64 byte count
  const std::string& bytes() const { return bytes_; }

 private:
  std::string element(const std::string& type, const std::string& name, int components,
                      const void* data, std::uint64_t size);
  std::string bytes_;
};

// the XML declaration and the VTKFile element's opening tag for a dataset type ("PolyData",
// "StructuredGrid"), little-endian with UInt64 headers
std::string vtk_file_open(const std::string& type);
// the AppendedData block and the VTKFile element's closing tag
std::string vtk_file_close(const VtkAppendedData& appended);

}  // namespace talus
