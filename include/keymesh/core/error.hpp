#pragma once
// Error types. Every failure the library can meet on bad input is an exception
// whose message names the file, the field and the value at fault; the CLI turns
// InputError into "keymesh: <message>" on stderr and exit code 1.
#include <stdexcept>
#include <string>

namespace keymesh {

// Bad or unsupported input data (a file, an array, a size): exit code 1.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A request that cannot be met with valid input (e.g. a size past a supported
// limit): also exit code 1, kept distinct so callers can tell them apart.
class LimitError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace keymesh
