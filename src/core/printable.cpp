#include "keymesh/core/printable.hpp"

namespace keymesh {

std::string printable(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (c >= 0x20 && c != 0x7f) {
      out += ch;
      continue;
    }
    out += '\\';
    if (c == '\n') out += 'n';
    else if (c == '\t') out += 't';
    else if (c == '\r') out += 'r';
    else {
      static const char kHex[] = "0123456789abcdef";
      out += 'x';
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return out;
}

}  // namespace keymesh
