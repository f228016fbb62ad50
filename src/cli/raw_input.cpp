#include "raw_input.hpp"

#include <exception>

namespace keymesh::cli {

void RawInputCli::add_options(Subcommand& cmd, const char* types) {
  auto* d = cmd.add_option("--dims", dims, "raw input: points along x y z")->expected(3);
  cmd.add_option("--type", type, std::string("raw input: ") + types)
      ->check(text_check(
          [](std::string& text) -> std::string {
            try {
              parse_scalar_type(text);
              return {};
            } catch (const std::exception& e) {
              return e.what();
            }
          },
          "TYPE"))
      ->needs(d);
  cmd.add_option("--spacing", spacing, "raw input: voxel spacing x y z")->expected(3)->needs(d);
  cmd.add_option("--origin", origin, "raw input: origin x y z")->expected(3)->needs(d);
  cmd.add_option("--endian", endian, "raw input: little or big")->check(member_of({"little", "big"}))->needs(d);
  cmd.add_option("--header-bytes", header_bytes, "raw input: bytes to skip")->needs(d)->check(non_negative());
}

io::RawOptions RawInputCli::options() const {
  io::RawOptions raw;
  raw.dims = {dims[0], dims[1], dims[2]};
  raw.type = parse_scalar_type(type);
  if (!spacing.empty()) raw.spacing = {spacing[0], spacing[1], spacing[2]};
  if (!origin.empty()) raw.origin = {origin[0], origin[1], origin[2]};
  raw.big_endian = endian == "big";
  raw.header_bytes = header_bytes;
  return raw;
}

}  // namespace keymesh::cli
