// One error type for the whole library: a message that names what failed and how to fix it.
#pragma once
#include <optional>
#include <stdexcept>
#include <string>

namespace talus {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// the symbolic name of an OpenCL status code, e.g. "CL_OUT_OF_RESOURCES"
const char* cl_status_name(int code);

}  // namespace talus

namespace talus {

// bad input from the user (a file, a field, a flag): the CLI exits with code 2
class InputError : public Error {
 public:
  using Error::Error;
};

// a number as messages show it: six significant digits ("%g": 31400000 is "3.14e+07", 0.25 is
// "0.25", NaN is "nan"), so a range or a bad value reads as the user wrote it, not as DBL_MAX's
// 309 digits or std::to_string's fixed six decimals
std::string message_number(double v);

// a user's text read as one finite number, the whole of it ("5kN", "1e3 N", "nan", "inf" and ""
// are not): the number, or nullopt. The one reading of numbers the flags and specs use
std::optional<double> finite_number_in(const std::string& text);

}  // namespace talus
