// VTK XML ImageData (.vti) as VTK 9 and ParaView write it; the XML and
// DataArray decoding is shared with .vtp (io/vtk_xml.hpp).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <optional>
#include <sstream>
#include <type_traits>

#include "keymesh/mesh/label_scalars.hpp"
#include "volume_formats.hpp"
#include "vtk_xml.hpp"
#include "vtk_xml_writer.hpp"

namespace keymesh::io {

namespace {

using namespace vtk_xml;

std::vector<double> numbers(const std::string& path, const std::string& what, const std::string* text, std::size_t n) {
  if (!text) throw InputError(path + ": <ImageData> has no " + what);
  std::istringstream in(*text);
  std::vector<double> v;
  for (std::string w; in >> w;) {
    char* end = nullptr;
    const double x = std::strtod(w.c_str(), &end);
    if (end == w.c_str() || *end != '\0' || !std::isfinite(x)) throw InputError(path + ": bad " + what + " '" + *text + "'");
    v.push_back(x);
  }
  if (v.size() != n) throw InputError(path + ": " + what + " has " + std::to_string(v.size()) + " values, expected " + std::to_string(n));
  return v;
}

// The XML part of a file whose arrays are appended: everything up to the
// AppendedData marker '_' (inclusive), or empty when the file has no
// appended section within its first MiB (then the arrays are inline).
std::string appended_head(const std::string& path, std::uint64_t file_bytes) {
  std::string head(static_cast<std::size_t>(std::min<std::uint64_t>(file_bytes, 1 << 20)), '\0');
  detail::read_exact(path, 0, head.data(), head.size(), "the XML header");
  const auto tag = head.find("<AppendedData");
  if (tag == std::string::npos) return {};
  const auto marker = head.find('_', head.find('>', tag));
  if (marker == std::string::npos) return {};
  head.resize(marker + 1);
  return head;
}

}  // namespace

namespace {

// Where the grid lies: WholeExtent's sizes, Origin and Spacing (|spacing|),
// the origin moved to the extent's lower corner.
struct VtiGeometry {
  std::vector<double> extent;
  std::array<Id, 3> dims{};
  std::array<double, 3> origin{0, 0, 0}, spacing{1, 1, 1};
};
VtiGeometry read_geometry(const std::string& path, const XmlNode& image) {
  VtiGeometry g;
  g.extent = numbers(path, "WholeExtent", image.attr("WholeExtent"), 6);
  for (int a = 0; a < 3; ++a) {
    const double d = g.extent[2 * a + 1] - g.extent[2 * a] + 1;
    if (d < 1 || d > 9.0e15 || g.extent[2 * a] != std::floor(g.extent[2 * a]) || d != std::floor(d))
      throw InputError(path + ": bad WholeExtent '" + *image.attr("WholeExtent") + "'");
    g.dims[a] = static_cast<Id>(d);
  }
  if (image.attr("Origin")) {
    const auto o = numbers(path, "Origin", image.attr("Origin"), 3);
    g.origin = {o[0], o[1], o[2]};
  }
  if (image.attr("Spacing")) {
    const auto s = numbers(path, "Spacing", image.attr("Spacing"), 3);
    for (int a = 0; a < 3; ++a) {
      if (!(s[a] != 0)) throw InputError(path + ": Spacing must not be zero");
      g.spacing[a] = std::abs(s[a]);
    }
  }
  // Point (i, j, k) of the extent lies at Origin + (i, j, k) * Spacing: the
  // grid's first point is the extent's lower corner.
  for (int a = 0; a < 3; ++a) g.origin[a] += g.extent[2 * a] * g.spacing[a];
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(g.origin[a])) throw InputError(path + ": Origin + WholeExtent * Spacing is not finite");
  return g;
}

// The one piece's scalar point array: the active Scalars, else the first.
const XmlNode& scalar_point_array(const std::string& path, const XmlNode& image, const std::vector<double>& extent) {
  const XmlNode* piece = image.child("Piece");
  if (!piece) throw InputError(path + ": <ImageData> has no <Piece>");
  if (piece->attr("Extent")) {
    const auto pe = numbers(path, "Piece Extent", piece->attr("Extent"), 6);
    if (pe != extent) throw InputError(path + ": multi-piece .vti files are not supported");
  }
  const XmlNode* point_data = piece->child("PointData");
  const XmlNode* array = nullptr;
  if (point_data) {
    if (const std::string* active = point_data->attr("Scalars")) array = named_array(point_data, *active);
    if (!array) array = point_data->child("DataArray");
  }
  if (!array) throw InputError(path + ": no point data array to contour");
  if (const std::string* nc = array->attr("NumberOfComponents"); nc && *nc != "1")
    throw InputError(path + ": point array has " + *nc + " components (a scalar field is needed)");
  return *array;
}

// Where a raw appended array's samples start in the file (after its size
// header), checked against the bytes the grid needs and the file holds.
std::uint64_t appended_samples_at(const std::string& path, const XmlNode& array, const Context& ctx,
                                  std::uint64_t head_bytes, std::uint64_t file_bytes, std::uint64_t need) {
  std::int64_t offset = 0;
  const std::string* off = array.attr("offset");
  if (!off || !mesh_bytes::parse_int64(*off, offset) || offset < 0)
    throw InputError(path + ": point array has a bad appended offset");
  const std::uint64_t at = head_bytes + static_cast<std::uint64_t>(offset);
  const std::size_t hs = ctx.header == ScalarType::UInt64 ? 8 : 4;
  unsigned char h[8] = {};
  detail::read_exact(path, at, h, hs, "the point array's size header");
  const std::uint64_t array_bytes = hs == 8 ? mesh_bytes::load<std::uint64_t>(h, ctx.big_endian)
                                            : mesh_bytes::load<std::uint32_t>(h, ctx.big_endian);
  if (array_bytes != need)
    throw InputError(path + ": point array holds " + std::to_string(array_bytes) + " bytes, WholeExtent needs " +
                     std::to_string(need));
  if (at + hs > file_bytes || need > file_bytes - at - hs)
    throw InputError(path + ": file holds " + std::to_string(file_bytes) + " bytes, the point array needs " +
                     std::to_string(need) + " at offset " + std::to_string(at + hs));
  return at + hs;
}

// A decoded array into the grid: as it is when it holds the declared type;
// ascii arrays decode as doubles and are converted back to the declared
// type, refusing values the type cannot hold (and NaN in an integer array).
void store_decoded(const std::string& path, const Array& a, ScalarType declared_scalar, const std::string& declared,
                   ImageGrid& grid) {
  if (a.type == declared_scalar) {
    std::memcpy(grid.data(), a.bytes.data(), grid.bytes.size());
    if (a.big) detail::swap_samples(grid);
    return;
  }
  visit_any_scalars(grid, [&](const auto* samples) {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(samples)>>;
    T* out = const_cast<T*>(samples);
    // 64-bit ids past 2^53 would not survive the ascii values' doubles.
    constexpr double kExact = sizeof(T) == 8 ? 9007199254740992.0 : 1e300;
    for (Id i = 0; i < grid.num_points(); ++i) {
      const double v = a.as_double(static_cast<std::size_t>(i));
      if constexpr (std::is_integral_v<T>) {
        if (!(v >= static_cast<double>(std::numeric_limits<T>::min()) &&
              v <= static_cast<double>(std::numeric_limits<T>::max()) && v > -kExact && v < kExact))
          throw InputError(path + ": point array value " + std::to_string(v) + " at index " + std::to_string(i) +
                           " does not fit its type " + declared +
                           (sizeof(T) == 8 ? " exactly (ascii 64-bit values within 2^53; write binary)" : ""));
      }
      out[i] = static_cast<T>(v);
    }
    return 0;
  });
}

// Parses a .vti from `data`: the whole file, or (head_only) just its XML
// head up to the AppendedData marker, in which case only an uncompressed
// raw appended array can be read (straight from the file into the grid)
// and anything else returns nullopt.
// With `layout`, a raw appended uncompressed array is not read: where its
// samples lie is filled in instead (vti_layout).
std::optional<ImageGrid> parse_vti(const std::string& path, std::string_view data, bool head_only,
                                   std::uint64_t file_bytes, VolumeLayout* layout = nullptr) {
  const ParsedXml xml = parse_xml(data, path);
  const Context ctx = file_context(xml, path, "ImageData");
  const XmlNode* image = xml.root->child("ImageData");
  if (!image) throw InputError(path + ": VTK file has no <ImageData>");
  const VtiGeometry geometry = read_geometry(path, *image);
  const XmlNode& array = scalar_point_array(path, *image, geometry.extent);
  const std::string* declared = array.attr("type");
  const auto declared_scalar = declared ? vtk_scalar(*declared) : std::nullopt;
  if (!declared_scalar) throw InputError(path + ": point array has no supported type");
  // Every type VTK names but the 64-bit ones keymesh has none for: UInt32,
  // Int64 and UInt64 are label maps (mesh/label_scalars.hpp).
  const ScalarType type = *declared_scalar;
  // Checks dims (and the product's overflow) before anything is allocated;
  // the samples are allocated only once the file is known to hold them.
  const std::uint64_t need = detail::checked_byte_count(geometry.dims, type, path);
  ImageGrid grid;
  grid.origin = geometry.origin;
  grid.spacing = geometry.spacing;
  grid.name = volume_field_name(array.attr("Name"));
  const std::string* format = array.attr("format");
  if (head_only && format && *format == "appended" && ctx.compressor.empty() && ctx.appended_encoding &&
      *ctx.appended_encoding == "raw") {
    // Raw appended, uncompressed: [size header][samples] at head + offset.
    const std::uint64_t at = appended_samples_at(path, array, ctx, data.size(), file_bytes, need);
    if (layout) {
      layout->data_path = path;
      layout->raw =
          RawOptions{geometry.dims, type, geometry.spacing, geometry.origin, ctx.big_endian, static_cast<Id>(at)};
      layout->name = grid.name;
      return std::nullopt;
    }
    detail::allocate_checked(grid, geometry.dims, type, path);
    detail::read_exact(path, at, grid.data(), grid.bytes.size(), "the point array");
    if (ctx.big_endian) detail::swap_samples(grid);
    return grid;
  }
  if (head_only) return std::nullopt;  // appended but compressed or base64: needs the whole file
  // Decoding checks every size against the bytes present, so the grid is
  // allocated only for data the file really holds.
  const Array a = decode_array(array, ctx, "point array", static_cast<std::int64_t>(need / scalar_size(type)));
  detail::allocate_checked(grid, geometry.dims, type, path);
  store_decoded(path, a, *declared_scalar, *declared, grid);
  return grid;
}

}  // namespace

ImageGrid read_vti(const std::string& path) {
  const std::uint64_t file_bytes = detail::file_size_or_throw(path);
  // Large volumes are written with raw appended data: parse only the XML
  // head and read the samples straight into the grid (no whole-file copy).
  const std::string head = appended_head(path, file_bytes);
  if (!head.empty())
    if (auto grid = parse_vti(path, head, true, file_bytes)) return std::move(*grid);
  return std::move(*parse_vti(path, mesh_bytes::read_whole_file(path), false, file_bytes));
}

VolumeLayout vti_layout(const std::string& path) {
  VolumeLayout layout;
  const std::uint64_t file_bytes = detail::file_size_or_throw(path);
  const std::string head = appended_head(path, file_bytes);
  if (!head.empty()) parse_vti(path, head, true, file_bytes, &layout);
  if (layout.data_path.empty()) layout.compressed = "inline, base64 or zlib-compressed .vti";
  return layout;
}

void write_vti(const ImageGrid& grid, const std::string& path) {
  char extent[256], geometry[512];
  std::snprintf(extent, sizeof extent, "0 %lld 0 %lld 0 %lld", static_cast<long long>(grid.dims[0] - 1),
                static_cast<long long>(grid.dims[1] - 1), static_cast<long long>(grid.dims[2] - 1));
  std::snprintf(geometry, sizeof geometry, "Origin=\"%.17g %.17g %.17g\" Spacing=\"%.17g %.17g %.17g\"", grid.origin[0],
                grid.origin[1], grid.origin[2], grid.spacing[0], grid.spacing[1], grid.spacing[2]);
  vtk_xml::AppendedArrays arrays;
  std::string head = vtk_xml::file_header("ImageData");
  head += std::string("  <ImageData WholeExtent=\"") + extent + "\" " + geometry + ">\n";
  head += std::string("    <Piece Extent=\"") + extent + "\">\n";
  head += "      <PointData Scalars=\"" + xml_escape(grid.name) + "\">\n";
  head += arrays.bytes(grid.type, grid.name, 1, grid.data(), grid.bytes.size());
  head += "      </PointData>\n      <CellData/>\n    </Piece>\n  </ImageData>\n";
  arrays.write(path, head);
}

}  // namespace keymesh::io
