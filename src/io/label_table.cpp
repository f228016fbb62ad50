// Label tables (keymesh/io/label_table.hpp).
#include "keymesh/io/label_table.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "keymesh/core/error.hpp"
#include "keymesh/core/printable.hpp"

namespace keymesh::io {

namespace {

std::string where(const std::string& path, long line) {
  return printable(path) + " line " + std::to_string(line);
}

// "ID NAME ...": the id and the name (the second whitespace-separated column).
std::pair<std::uint64_t, std::string> parse_line(const std::string& text, const std::string& path, long line) {
  std::istringstream in(text);
  std::string id, name;
  in >> id >> name;
  const bool digits = !id.empty() && id.size() <= 20 &&
                      std::all_of(id.begin(), id.end(), [](unsigned char c) { return std::isdigit(c) != 0; });
  errno = 0;
  const unsigned long long value = digits ? std::strtoull(id.c_str(), nullptr, 10) : 0;
  if (!digits || errno == ERANGE)
    throw InputError(where(path, line) + ": '" + printable(id) + "' is not a label id (a non-negative integer below 2^64)");
  if (name.empty()) throw InputError(where(path, line) + ": label " + id + " has no name");
  return {static_cast<std::uint64_t>(value), name};
}

}  // namespace

std::map<std::uint64_t, std::string> read_label_table(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(printable(path) + ": cannot read the label table");
  std::map<std::uint64_t, std::string> names;
  std::string text;
  for (long line = 1; std::getline(in, text); ++line) {
    const auto first = text.find_first_not_of(" \t\r");
    if (first == std::string::npos || text[first] == '#') continue;
    auto [id, name] = parse_line(text, path, line);
    if (!names.emplace(id, name).second)
      throw InputError(where(path, line) + ": label " + std::to_string(id) + " is named twice");
  }
  if (in.bad()) throw InputError(printable(path) + ": read failed");
  return names;
}

std::string label_table_beside(const std::string& volume_path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  std::string candidates[2] = {volume_path + ".txt", ""};
  const std::string gz = ".gz";
  if (volume_path.size() > gz.size() && volume_path.compare(volume_path.size() - gz.size(), gz.size(), gz) == 0)
    candidates[1] = volume_path.substr(0, volume_path.size() - gz.size()) + ".txt";
  for (const std::string& c : candidates)
    if (!c.empty() && fs::is_regular_file(c, ec)) return c;
  return {};
}

}  // namespace keymesh::io
