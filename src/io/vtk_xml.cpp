#include "vtk_xml.hpp"

#include <bit>
#include <limits>

#include "keymesh/core/error.hpp"

namespace keymesh::io::vtk_xml {

using namespace mesh_bytes;

// ---- a minimal XML reader -------------------------------------------------
// Enough for VTK's XML files: elements, attributes, direct text; the
// <AppendedData> section is cut off before parsing because raw appended
// bytes may contain anything, including '<'.


std::string xml_unescape(std::string_view s, const std::string& path) {
  std::string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '&') {
      out += s[i];
      continue;
    }
    const std::size_t semi = s.find(';', i);
    if (semi == std::string_view::npos) throw InputError(path + ": bad XML entity");
    const std::string_view ent = s.substr(i + 1, semi - i - 1);
    if (ent == "lt") out += '<';
    else if (ent == "gt") out += '>';
    else if (ent == "amp") out += '&';
    else if (ent == "quot") out += '"';
    else if (ent == "apos") out += '\'';
    else if (ent.size() > 1 && ent[0] == '#') {
      std::int64_t code = 0;
      const bool hex = ent.size() > 2 && (ent[1] == 'x' || ent[1] == 'X');
      const std::string digits(ent.substr(hex ? 2 : 1));
      char* end = nullptr;
      code = std::strtoll(digits.c_str(), &end, hex ? 16 : 10);
      if (digits.empty() || *end != '\0' || code <= 0 || code > 0x10FFFF) throw InputError(path + ": bad XML entity");
      // UTF-8 encode
      const auto c = static_cast<std::uint32_t>(code);
      if (c < 0x80) out += static_cast<char>(c);
      else if (c < 0x800) {
        out += static_cast<char>(0xC0 | (c >> 6));
        out += static_cast<char>(0x80 | (c & 0x3F));
      } else if (c < 0x10000) {
        out += static_cast<char>(0xE0 | (c >> 12));
        out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
        out += static_cast<char>(0x80 | (c & 0x3F));
      } else {
        out += static_cast<char>(0xF0 | (c >> 18));
        out += static_cast<char>(0x80 | ((c >> 12) & 0x3F));
        out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
        out += static_cast<char>(0x80 | (c & 0x3F));
      }
    } else {
      throw InputError(path + ": unknown XML entity '&" + std::string(ent.substr(0, 20)) + ";'");
    }
    i = semi;
  }
  return out;
}

std::string xml_escape(std::string_view s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}


XmlNode::~XmlNode() {
  // Detach every descendant into a flat list first, so each node is
  // destroyed with no children left and the recursion stops at one level.
  std::vector<std::unique_ptr<XmlNode>> pending = std::move(children);
  while (!pending.empty()) {
    std::unique_ptr<XmlNode> node = std::move(pending.back());
    pending.pop_back();
    for (auto& c : node->children) pending.push_back(std::move(c));
    node->children.clear();
  }
}

bool is_name_char(char c) {
  return !is_space(c) && c != '=' && c != '>' && c != '/' && c != '<' && c != '"' && c != '\'';
}

namespace {

// parse_xml's state: the document, where it is, the elements still open and
// what has been built.
class XmlScanner {
 public:
  XmlScanner(std::string_view doc, const std::string& path) : doc_(doc), path_(path) {}

  ParsedXml run() {
    while (pos_ < doc_.size()) {
      const std::size_t lt = doc_.find('<', pos_);
      const std::size_t text_end = lt == std::string_view::npos ? doc_.size() : lt;
      if (!stack_.empty() && text_end > pos_) stack_.back()->text.append(doc_.substr(pos_, text_end - pos_));
      if (lt == std::string_view::npos) break;
      pos_ = lt;
      if (skip_comment_or_declaration()) continue;
      if (doc_.substr(pos_, 2) == "</") {
        end_tag();
        continue;
      }
      if (start_tag()) return std::move(result_);  // the appended data follows
    }
    if (!result_.root) throw InputError(path_ + ": not an XML file (no root element)");
    if (!stack_.empty()) throw InputError(path_ + ": truncated XML (<" + stack_.back()->name + "> not closed)");
    return std::move(result_);
  }

 private:
  InputError fail(const std::string& what) const {
    return InputError(path_ + ": malformed XML at byte " + std::to_string(pos_) + ": " + what);
  }
  void skip_space() {
    while (pos_ < doc_.size() && is_space(doc_[pos_])) ++pos_;
  }
  std::string_view name_at() {
    const std::size_t start = pos_;
    while (pos_ < doc_.size() && is_name_char(doc_[pos_])) ++pos_;
    return doc_.substr(start, pos_ - start);
  }

  // <!-- ... -->, <? ... ?> and <! ... >: skipped; false when pos_ starts none.
  bool skip_comment_or_declaration() {
    if (doc_.substr(pos_, 4) == "<!--") {
      const std::size_t e = doc_.find("-->", pos_ + 4);
      if (e == std::string_view::npos) throw fail("unterminated comment");
      pos_ = e + 3;
      return true;
    }
    if (doc_.substr(pos_, 2) == "<?" || doc_.substr(pos_, 2) == "<!") {
      const std::size_t e = doc_.find('>', pos_);
      if (e == std::string_view::npos) throw fail("unterminated declaration");
      pos_ = e + 1;
      return true;
    }
    return false;
  }

  // </name>: closes the innermost open element, which must be `name`.
  void end_tag() {
    const std::size_t e = doc_.find('>', pos_);
    if (e == std::string_view::npos) throw fail("unterminated end tag");
    std::string_view name = doc_.substr(pos_ + 2, e - pos_ - 2);
    while (!name.empty() && is_space(name.back())) name.remove_suffix(1);
    if (stack_.empty() || stack_.back()->name != name)
      throw fail("end tag </" + std::string(name.substr(0, 40)) + "> does not match");
    stack_.pop_back();
    pos_ = e + 1;
  }

  // key="value" (or 'value') into node.attrs, unescaped.
  void read_attribute(XmlNode& node) {
    const std::string key(name_at());
    if (key.empty()) throw fail("bad attribute in <" + node.name + ">");
    skip_space();
    if (pos_ >= doc_.size() || doc_[pos_] != '=') throw fail("attribute '" + key + "' without value");
    ++pos_;
    skip_space();
    if (pos_ >= doc_.size() || (doc_[pos_] != '"' && doc_[pos_] != '\''))
      throw fail("unquoted attribute '" + key + "'");
    const char quote = doc_[pos_++];
    const std::size_t ve = doc_.find(quote, pos_);
    if (ve == std::string_view::npos) throw fail("unterminated attribute '" + key + "'");
    node.attrs.emplace_back(key, xml_unescape(doc_.substr(pos_, ve - pos_), path_));
    pos_ = ve + 1;
  }

  // The attributes up to '>' or '/>'; true for a self-closing tag.
  bool read_attributes(XmlNode& node) {
    for (;;) {
      skip_space();
      if (pos_ >= doc_.size()) throw fail("unterminated tag <" + node.name + ">");
      if (doc_[pos_] == '>') {
        ++pos_;
        return false;
      }
      if (doc_[pos_] == '/') {
        if (pos_ + 1 >= doc_.size() || doc_[pos_ + 1] != '>') throw fail("stray '/' in tag");
        pos_ += 2;
        return true;
      }
      read_attribute(node);
    }
  }

  // A start tag at pos_: the element joins its parent (or is the root) and,
  // unless self-closing, is open until its end tag. True for <AppendedData>:
  // everything after its '_' marker is data, cut off unparsed.
  bool start_tag() {
    ++pos_;
    auto node = std::make_unique<XmlNode>();
    node->name = std::string(name_at());
    if (node->name.empty()) throw fail("empty tag name");
    const bool self_closing = read_attributes(*node);
    XmlNode* raw = node.get();
    if (stack_.empty()) {
      if (result_.root) throw fail("more than one root element");
      result_.root = std::move(node);
    } else {
      stack_.back()->children.push_back(std::move(node));
    }
    if (raw->name == "AppendedData" && !self_closing) {
      const std::string* enc = raw->attr("encoding");
      result_.appended_encoding = enc ? *enc : std::string("raw");
      skip_space();
      if (pos_ >= doc_.size() || doc_[pos_] != '_') throw fail("<AppendedData> without '_' marker");
      result_.appended = doc_.substr(pos_ + 1);
      return true;
    }
    if (!self_closing) {
      if (stack_.size() >= kMaxXmlDepth)
        throw fail("elements nested deeper than " + std::to_string(kMaxXmlDepth) + " levels");
      stack_.push_back(raw);
    }
    return false;
  }

  std::string_view doc_;
  const std::string& path_;
  std::size_t pos_ = 0;
  std::vector<XmlNode*> stack_;
  ParsedXml result_;
};

}  // namespace

ParsedXml parse_xml(std::string_view doc, const std::string& path) { return XmlScanner(doc, path).run(); }

// ---- DataArray decoding ---------------------------------------------------

namespace {
// VTK's DataArray type names, in ScalarType's order.
constexpr const char* kVtkTypeNames[] = {"UInt8",   "Int8",    "UInt16", "Int16", "Int32",
                                         "Float32", "Float64", "UInt32", "Int64", "UInt64"};
}  // namespace

const char* vtk_type_name(ScalarType s) { return kVtkTypeNames[static_cast<std::size_t>(s)]; }

std::optional<ScalarType> vtk_scalar(std::string_view t) {
  if (t == "Char") return ScalarType::Int8;  // VTK's legacy name of Int8
  for (std::size_t i = 0; i < std::size(kVtkTypeNames); ++i)
    if (t == kVtkTypeNames[i]) return static_cast<ScalarType>(i);
  return std::nullopt;
}



// Appended raw bytes as a source of the same shape as Base64Reader.
class RawSource {
 public:
  RawSource(std::string_view data, const std::string& path) : cursor_(data, path) {}
  void read(std::size_t n, std::string& out, std::string_view what) { out.append(cursor_.take(n, what), n); }
  std::size_t max_remaining() const { return cursor_.remaining(); }

 private:
  ByteCursor cursor_;
};

std::uint64_t header_value(const std::string& h, std::size_t i, const Context& ctx) {
  return ctx.header == ScalarType::UInt64 ? load<std::uint64_t>(h.data() + 8 * i, ctx.big_endian)
                                      : load<std::uint32_t>(h.data() + 4 * i, ctx.big_endian);
}

// Reads one binary block (VTK's layout: a size header, or the compression
// header and zlib blocks) from src.
template <class Source>
std::string read_binary_block(Source& src, const Context& ctx, const std::string& what) {
  const std::size_t hs = scalar_size(ctx.header);
  std::string h;
  src.read(hs, h, what);
  const std::uint64_t first = header_value(h, 0, ctx);
  std::string out;
  if (ctx.compressor.empty()) {
    if (first > src.max_remaining())
      throw InputError(ctx.path + ": " + what + " declares " + std::to_string(first) + " bytes, more than the file holds");
    src.read(static_cast<std::size_t>(first), out, what);
    return out;
  }
  if (ctx.compressor != "vtkZLibDataCompressor")
    throw InputError(ctx.path + ": unsupported compressor '" + ctx.compressor + "' (only vtkZLibDataCompressor)");
  const std::uint64_t blocks = first;
  if (blocks > src.max_remaining() / hs)
    throw InputError(ctx.path + ": " + what + " declares " + std::to_string(blocks) + " compressed blocks, more than the file holds");
  h.clear();
  src.read(static_cast<std::size_t>(hs * (2 + blocks)), h, what);
  const std::uint64_t block_size = header_value(h, 0, ctx);
  const std::uint64_t last_size = header_value(h, 1, ctx);
  std::uint64_t compressed_total = 0;
  for (std::uint64_t b = 0; b < blocks && compressed_total <= src.max_remaining(); ++b) {
    const std::uint64_t c = header_value(h, 2 + b, ctx);
    compressed_total = c > src.max_remaining() ? c : compressed_total + c;  // no wrap-around
  }
  if (compressed_total > src.max_remaining())
    throw InputError(ctx.path + ": " + what + " declares " + std::to_string(compressed_total) +
                     " compressed bytes, more than the file holds");
  if (blocks == 0) return out;
  if (last_size > block_size) throw InputError(ctx.path + ": " + what + ": bad compression header");
  const std::uint64_t last = last_size == 0 ? block_size : last_size;
  if (block_size > 0 && blocks - 1 > (std::numeric_limits<std::uint64_t>::max() - last) / block_size)
    throw InputError(ctx.path + ": " + what + ": " + std::to_string(blocks) + " blocks of " + std::to_string(block_size) +
                     " bytes overflow");
  const std::uint64_t total = (blocks - 1) * block_size + last;
  // zlib cannot expand by more than about 1032:1; anything beyond is a lie
  // that would otherwise make us allocate absurd buffers.
  if (block_size > (std::uint64_t{1} << 40) || total / 1032 > compressed_total + 64)
    throw InputError(ctx.path + ": " + what + " declares " + std::to_string(total) +
                     " uncompressed bytes, impossible for its compressed size");
  // No reserve(total): the output grows with what zlib_inflate really inflates.
  std::string chunk;
  for (std::uint64_t b = 0; b < blocks; ++b) {
    chunk.clear();
    src.read(static_cast<std::size_t>(header_value(h, 2 + b, ctx)), chunk, what);
    // Each block on its own too: a block cannot inflate past ~1032:1.
    const std::uint64_t expect = b + 1 == blocks ? last : block_size;
    if (expect / 1032 > chunk.size() + 64)
      throw InputError(ctx.path + ": " + what + " block " + std::to_string(b) + " declares " + std::to_string(expect) +
                       " uncompressed bytes, impossible for its " + std::to_string(chunk.size()) + " compressed bytes");
    zlib_inflate(chunk.data(), chunk.size(), static_cast<std::size_t>(b + 1 == blocks ? last : block_size), out, ctx.path,
                 what);
  }
  return out;
}

// Decodes a <DataArray>. `expected` is the value count when known (-1 when not).
Array decode_array(const XmlNode& node, const Context& ctx, const std::string& what_in, std::int64_t expected) {
  const std::string* name = node.attr("Name");
  const std::string what = what_in + (name ? " '" + *name + "'" : std::string());
  const std::string* type_attr = node.attr("type");
  if (!type_attr) throw InputError(ctx.path + ": " + what + " has no type");
  const auto type = vtk_scalar(*type_attr);
  if (!type) throw InputError(ctx.path + ": " + what + " has unsupported type '" + *type_attr + "'");
  Array a;
  a.type = *type;
  a.big = ctx.big_endian;
  if (const std::string* nc = node.attr("NumberOfComponents")) {
    std::int64_t c = 0;
    if (!parse_int64(*nc, c) || c < 1 || c > 4096) throw InputError(ctx.path + ": " + what + " has bad NumberOfComponents");
    a.components = static_cast<int>(c);
  }
  const std::string* fmt = node.attr("format");
  const std::string format = fmt ? *fmt : std::string("ascii");
  if (format == "ascii") {
    TokenCursor tok(node.text);
    a.type = ScalarType::Float64;
    a.big = std::endian::native == std::endian::big;
    std::string_view t;
    while (!(t = tok.next()).empty()) {
      double v = 0;
      if (!parse_double(t, v)) throw InputError(ctx.path + ": " + what + ": bad number '" + std::string(t.substr(0, 40)) + "'");
      a.bytes.append(reinterpret_cast<const char*>(&v), sizeof v);
    }
  } else if (format == "binary") {
    Base64Reader src(node.text, ctx.path);
    a.bytes = read_binary_block(src, ctx, what);
  } else if (format == "appended") {
    if (!ctx.appended_encoding) throw InputError(ctx.path + ": " + what + " is appended but the file has no <AppendedData>");
    const std::string* off = node.attr("offset");
    std::int64_t offset = 0;
    if (!off || !parse_int64(*off, offset) || offset < 0 || static_cast<std::uint64_t>(offset) > ctx.appended.size())
      throw InputError(ctx.path + ": " + what + " has a bad appended offset");
    const std::string_view rest = ctx.appended.substr(static_cast<std::size_t>(offset));
    if (*ctx.appended_encoding == "raw") {
      RawSource src(rest, ctx.path);
      a.bytes = read_binary_block(src, ctx, what);
    } else if (*ctx.appended_encoding == "base64") {
      Base64Reader src(rest, ctx.path);
      a.bytes = read_binary_block(src, ctx, what);
    } else {
      throw InputError(ctx.path + ": unsupported AppendedData encoding '" + *ctx.appended_encoding + "'");
    }
  } else {
    throw InputError(ctx.path + ": " + what + " has unsupported format '" + format + "'");
  }
  if (a.bytes.size() % scalar_size(a.type) != 0)
    throw InputError(ctx.path + ": " + what + " holds " + std::to_string(a.bytes.size()) + " bytes, not a whole number of " +
                     *type_attr + " values");
  if (expected >= 0 && a.count() != static_cast<std::uint64_t>(expected))
    throw InputError(ctx.path + ": " + what + " holds " + std::to_string(a.count()) + " values, expected " +
                     std::to_string(expected));
  return a;
}

std::int64_t count_attr(const XmlNode& node, std::string_view key, const std::string& path) {
  const std::string* v = node.attr(key);
  if (!v) return 0;
  std::int64_t n = 0;
  // 2^48 bounds every product taken from a count (3 * points, ...) far from overflow.
  if (!parse_int64(*v, n) || n < 0 || n > (std::int64_t{1} << 48)) throw InputError(path + ": bad " + std::string(key) + " '" + v->substr(0, 40) + "'");
  return n;
}

const XmlNode* named_array(const XmlNode* section, std::string_view name) {
  if (!section) return nullptr;
  for (const auto& c : section->children)
    if (c->name == "DataArray") {
      const std::string* n = c->attr("Name");
      if (n && *n == name) return c.get();
    }
  return nullptr;
}


Context file_context(const ParsedXml& xml, const std::string& path, std::string_view type) {
  const XmlNode& root = *xml.root;
  if (root.name != "VTKFile") throw InputError(path + ": not a VTK XML file (root <" + root.name + ">)");
  const std::string* t = root.attr("type");
  if (!t || *t != type)
    throw InputError(path + ": VTK file type '" + (t ? *t : std::string("?")) + "' is not " + std::string(type));
  Context ctx{path, false, ScalarType::UInt32, {}, {}, {}};
  if (const std::string* bo = root.attr("byte_order")) {
    if (*bo == "BigEndian") ctx.big_endian = true;
    else if (*bo != "LittleEndian") throw InputError(path + ": unknown byte_order '" + *bo + "'");
  }
  if (const std::string* ht = root.attr("header_type")) {
    if (*ht == "UInt64") ctx.header = ScalarType::UInt64;
    else if (*ht != "UInt32") throw InputError(path + ": unsupported header_type '" + *ht + "'");
  }
  if (const std::string* comp = root.attr("compressor")) ctx.compressor = *comp;
  ctx.appended_encoding = xml.appended_encoding;
  ctx.appended = xml.appended;
  return ctx;
}

}  // namespace keymesh::io::vtk_xml
