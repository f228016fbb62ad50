#pragma once
// A structure-aware mutator for the VTK XML formats (.vti, .vtp, .vtu):
// byte flips rarely get past the XML parser, so half of the mutations here
// edit the document as XML instead, aiming at the classes of issue 19:
//   - deep nesting: an element's start tag repeated thousands of times;
//   - attribute lies: a count, offset, extent, type, format or byte order
//     replaced by a hostile value (0, -1, 2^31, 2^48, 2^63, nan, 1e39, ...);
//   - broken structure: a closing tag dropped or duplicated, an element cut.
// The other half is libFuzzer's own byte-level mutation. Deterministic for a
// given seed, as libFuzzer requires. Include it in a target built with
// KEYMESH_LIBFUZZER after fuzz_target.hpp: it defines LLVMFuzzerCustomMutator.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#ifdef KEYMESH_LIBFUZZER

extern "C" std::size_t LLVMFuzzerMutate(std::uint8_t* data, std::size_t size, std::size_t max_size);

namespace keymesh::fuzz::xml {

// Positions of every '<' that starts a start tag ("<Name", not "</", "<?", "<!").
inline std::vector<std::size_t> start_tags(const std::string& doc) {
  std::vector<std::size_t> out;
  for (std::size_t p = doc.find('<'); p != std::string::npos; p = doc.find('<', p + 1))
    if (p + 1 < doc.size() && doc[p + 1] != '/' && doc[p + 1] != '?' && doc[p + 1] != '!') out.push_back(p);
  return out;
}

// Positions of every attribute value (the character after the opening quote
// of name="value"), with the value's length.
inline std::vector<std::pair<std::size_t, std::size_t>> attribute_values(const std::string& doc) {
  std::vector<std::pair<std::size_t, std::size_t>> out;
  for (std::size_t p = doc.find("=\""); p != std::string::npos; p = doc.find("=\"", p + 2)) {
    const std::size_t end = doc.find('"', p + 2);
    if (end == std::string::npos) break;
    out.emplace_back(p + 2, end - p - 2);
  }
  return out;
}

inline std::string mutate(std::string doc, std::mt19937& rng) {
  static const char* kLies[] = {"0", "-1", "1", "2147483648", "4294967296", "281474976710656",
                                "9223372036854775807", "18446744073709551616", "nan", "inf", "1e39", "-1e39",
                                "0 -1 0 -1 0 -1", "0 2147483647 0 2147483647 0 2147483647", "",
                                "Float16", "Int64", "UInt64", "ascii", "binary", "appended", "BigEndian",
                                "vtkLZ4DataCompressor", "vtkZLibDataCompressor", "UInt32"};
  auto pick = [&](std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng); };
  switch (pick(4)) {
    case 0: {  // deep nesting: one start tag repeated
      const auto tags = start_tags(doc);
      if (tags.empty()) break;
      const std::size_t at = tags[pick(tags.size())];
      std::size_t name_end = at + 1;
      while (name_end < doc.size() && doc[name_end] != ' ' && doc[name_end] != '>' && doc[name_end] != '/') ++name_end;
      const std::string open = doc.substr(at, name_end - at) + ">";
      const std::size_t times = std::size_t(1) << pick(16);  // 1 .. 32768 levels
      std::string nest;
      for (std::size_t i = 0; i < times && nest.size() < 400000; ++i) nest += open;
      doc.insert(at, nest);
      break;
    }
    case 1:
    case 2: {  // an attribute lie
      const auto values = attribute_values(doc);
      if (values.empty()) break;
      const auto [at, length] = values[pick(values.size())];
      doc.replace(at, length, kLies[pick(sizeof kLies / sizeof *kLies)]);
      break;
    }
    default: {  // broken structure: drop, duplicate or cut at a tag
      const std::size_t close = doc.find("</", pick(doc.size() + 1));
      if (close == std::string::npos) break;
      const std::size_t end = doc.find('>', close);
      if (end == std::string::npos) break;
      const std::string tag = doc.substr(close, end + 1 - close);
      switch (pick(3)) {
        case 0: doc.erase(close, tag.size()); break;
        case 1: doc.insert(close, tag); break;
        default: doc.resize(close); break;
      }
    }
  }
  return doc;
}

}  // namespace keymesh::fuzz::xml

extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size, std::size_t max_size,
                                               unsigned int seed) {
  std::mt19937 rng(seed);
  if (rng() % 2 == 0) return LLVMFuzzerMutate(data, size, max_size);
  std::string doc = keymesh::fuzz::xml::mutate(std::string(reinterpret_cast<const char*>(data), size), rng);
  if (doc.size() > max_size) doc.resize(max_size);
  std::memcpy(data, doc.data(), doc.size());
  return doc.size();
}

#endif  // KEYMESH_LIBFUZZER
