#include "integer_options.hpp"

#include <cctype>
#include <cerrno>
#include <cstdlib>

namespace keymesh::cli {

std::string integer_text_error(std::string& text, bool is_unsigned) {
  const std::string typed = text;
  std::size_t digits = text.empty() || (text[0] != '+' && text[0] != '-') ? 0 : 1;
  const bool negative = digits == 1 && text[0] == '-';
  bool decimal = digits < text.size();
  for (std::size_t i = digits; i < text.size(); ++i)
    decimal = decimal && std::isdigit(static_cast<unsigned char>(text[i]));
  if (decimal) {  // "007" means 7, not octal
    const std::size_t first = text.find_first_not_of('0', digits);
    text.erase(digits, (first == std::string::npos ? text.size() - 1 : first) - digits);
  }
  if (negative && is_unsigned) return typed + " is negative; expected 0 or more";
  errno = 0;
  char* end = nullptr;
  if (is_unsigned)
    (void)std::strtoull(text.c_str(), &end, 0);
  else
    (void)std::strtoll(text.c_str(), &end, 0);
  if (errno == ERANGE)
    return typed + " is out of range (" +
           (is_unsigned ? std::string("0 to 18446744073709551615") : "-9223372036854775808 to 9223372036854775807") +
           ")";
  return {};  // not a number at all: CLI11 says so
}

void refuse_out_of_range_integers(Subcommand& cmd) {
  for (Option& opt : cmd.options()) {
    const std::string type = opt.get_type_name();
    const std::string base = type.substr(0, type.find(':'));
    if (base != "INT" && base != "UINT") continue;
    const bool is_unsigned = base == "UINT";
    // A transform (checks may not rewrite the text), run before the
    // option's own checks; no description: its help keeps its type as it was.
    opt.transform(text_check([is_unsigned](std::string& text) { return integer_text_error(text, is_unsigned); }, ""));
  }
}

}  // namespace keymesh::cli
