#pragma once
// The options that describe a headerless .raw volume (--dims, --type,
// --spacing, --origin, --endian, --header-bytes), shared by the subcommands
// that read volumes.
#include <string>
#include <vector>

#include "keymesh/io/volume_io.hpp"
#include "subcommand.hpp"

namespace keymesh::cli {

struct RawInputCli {
  std::vector<long long> dims;
  std::string type = "float32";
  std::vector<double> spacing, origin;
  std::string endian = "little";
  long long header_bytes = 0;

  // Adds the six options to `cmd`; every one but --dims needs --dims.
  // `types` lists the accepted sample types in --type's help.
  void add_options(Subcommand& cmd, const char* types = "uint8 int8 uint16 int16 int32 float32 float64");
  // True when --dims was given: the input is raw.
  bool given() const { return !dims.empty(); }
  // The reader's description of the raw file (call only when given()).
  io::RawOptions options() const;
};

}  // namespace keymesh::cli
