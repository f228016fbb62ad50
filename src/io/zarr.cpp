#include "zarr.hpp"

#if defined(KEYMESH_HAVE_BLOSC)
#include <blosc.h>
#endif
#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <optional>
#include <vector>

#include <nlohmann/json.hpp>

#include "keymesh/core/error.hpp"
#include "keymesh/mesh/label_scalars.hpp"
#include "mesh_bytes.hpp"
#include "volume_formats.hpp"
#include "whole_inflate.hpp"
#include "zarr_chunk_listing.hpp"

#include "type_names.hpp"

namespace keymesh::io {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// A decoded chunk larger than this is refused: it would be allocated whole.
constexpr std::uint64_t kMaxChunkBytes = std::uint64_t{1} << 30;
// Zarr and OME metadata nest a few levels; nlohmann's dump() (the messages
// quote a bad value) recurses per level: "filters" nested 100,000 deep
// overflowed the stack (exit 139).
constexpr int kMaxJsonDepth = 64;

json read_json(const std::string& file, const std::string& folder) {
  const mesh_bytes::FileBytes text = mesh_bytes::read_whole_file(file);
  const std::string name = fs::path(file).filename().string();
  try {
    return json::parse(text.view(), [&](int depth, json::parse_event_t, json&) {
      if (depth > kMaxJsonDepth)
        throw InputError(folder + ": " + name + " nests deeper than " + std::to_string(kMaxJsonDepth) + " levels");
      return true;
    });
  } catch (const json::exception& e) {
    throw InputError(folder + ": " + name + " is not valid JSON (" + e.what() + ")");
  }
}

bool path_exists(const fs::path& p) {
  std::error_code ec;
  return fs::exists(p, ec);
}

enum class Codec { None, Zlib, Blosc };

// The scale and translation of one OME coordinateTransformations list.
void apply_transforms(const json& list, std::vector<double>& scale, std::vector<double>& shift,
                      const std::string& folder) {
  if (!list.is_array()) return;
  for (const json& t : list) {
    if (!t.is_object() || !t.contains("type")) continue;
    const std::string type = t["type"].is_string() ? t["type"].get<std::string>() : "";
    const char* key = type == "scale" ? "scale" : type == "translation" ? "translation" : nullptr;
    if (!key) continue;
    if (!t.contains(key)) continue;  // a transform given by "path" is not supported: ignored
    const json& v = t[key];
    if (!v.is_array() || v.size() != scale.size())
      throw InputError(folder + ": OME " + type + " has " + std::to_string(v.is_array() ? v.size() : 0) +
                       " entries for " + std::to_string(scale.size()) + " axes");
    for (std::size_t a = 0; a < scale.size(); ++a) {
      if (!v[a].is_number()) throw InputError(folder + ": OME " + type + " entry is not a number");
      const double x = v[a].get<double>();
      if (type == "scale") {
        scale[a] *= x;
        shift[a] *= x;
      } else {
        shift[a] += x;
      }
    }
  }
}

class ZarrPlanes : public PlaneSource {
 public:
  explicit ZarrPlanes(const std::string& folder) : folder_(folder) {
    // A metadata value of the wrong JSON type (a string where a number is
    // due) surfaces as nlohmann's type_error: named as bad metadata.
    try {
      parse_metadata();
    } catch (const json::exception& e) {
      throw InputError(folder + ": Zarr metadata of an unexpected type (" + e.what() + ")");
    }
  }

  const ImageGrid& header() const override { return head_; }

  void read_planes(Id first, Id count, std::byte* out) override {
    const std::size_t n = shape_.size();
    const Id nx = head_.dims[0], ny = head_.dims[1];
    const Id cz = chunks_[n - 3], cy = chunks_[n - 2], cx = chunks_[n - 1];
    const std::size_t size = scalar_size(head_.type);
    // Sized by the first chunk stored on disk: absent chunks are filled in
    // place, so an array of fill_value allocates no chunk at all.
    std::vector<std::byte> chunk;
    if (listing_->none_stored()) {  // an array of fill_value: no chunk key to build and look up
      const std::size_t total = static_cast<std::size_t>(count * nx * ny) * size;
      for (std::size_t i = 0; i < total; i += size) std::memcpy(out + i, fill_.data(), size);
      if (swap_)
        for (std::size_t i = 0; i < total; i += size) std::reverse(out + i, out + i + size);
      return;
    }
    for (Id iz = first / cz; iz * cz < first + count; ++iz)
      for (Id iy = 0; iy * cy < ny; ++iy)
        for (Id ix = 0; ix * cx < nx; ++ix) {
          const bool stored = decode_chunk({iz, iy, ix}, chunk);
          const Id z0 = std::max(first, iz * cz), z1 = std::min(first + count, (iz + 1) * cz);
          const Id y1 = std::min(ny, (iy + 1) * cy), x1 = std::min(nx, (ix + 1) * cx);
          const std::size_t run = static_cast<std::size_t>(x1 - ix * cx) * size;
          for (Id z = z0; z < z1; ++z)
            for (Id y = iy * cy; y < y1; ++y) {
              const std::size_t src = static_cast<std::size_t>(((z - iz * cz) * cy + (y - iy * cy)) * cx) * size;
              const std::size_t dst = static_cast<std::size_t>(((z - first) * ny + y) * nx + ix * cx) * size;
              if (stored) std::memcpy(out + dst, chunk.data() + src, run);
              else
                for (std::size_t i = 0; i < run; i += size) std::memcpy(out + dst + i, fill_.data(), size);
            }
        }
    if (swap_) {
      const std::size_t total = static_cast<std::size_t>(count * nx * ny) * size;
      for (std::size_t i = 0; i < total; i += size) std::reverse(out + i, out + i + size);
    }
  }

 private:
  void parse_metadata() {
    const std::string& folder = folder_;
    fs::path array = folder;
    const json* level_transforms = nullptr;
    const json* multiscale = nullptr;
    json group;
    if (!path_exists(array / ".zarray")) {
      if (!path_exists(array / ".zattrs"))
        throw InputError(folder + ": not a Zarr array (no .zarray) nor an OME-Zarr image (no .zattrs)");
      group = read_json((array / ".zattrs").string(), folder);
      if (!group.contains("multiscales") || !group["multiscales"].is_array() || group["multiscales"].empty())
        throw InputError(folder + ": .zattrs has no OME multiscales (give the folder of a Zarr array)");
      multiscale = &group["multiscales"][0];
      if (!multiscale->contains("datasets") || !(*multiscale)["datasets"].is_array() ||
          (*multiscale)["datasets"].empty() || !(*multiscale)["datasets"][0].contains("path") ||
          !(*multiscale)["datasets"][0]["path"].is_string())
        throw InputError(folder + ": OME multiscales lists no dataset path");
      const json& level = (*multiscale)["datasets"][0];
      level_transforms = level.contains("coordinateTransformations") ? &level["coordinateTransformations"] : nullptr;
      array /= level["path"].get<std::string>();
      if (!path_exists(array / ".zarray"))
        throw InputError(folder + ": OME level '" + level["path"].get<std::string>() + "' has no .zarray");
    } else if (path_exists(array.parent_path() / ".zattrs")) {
      // A level's own folder: its transforms are in the image's .zattrs.
      group = read_json((array.parent_path() / ".zattrs").string(), folder);
      if (group.contains("multiscales") && group["multiscales"].is_array() && !group["multiscales"].empty()) {
        const json& ms = group["multiscales"][0];
        if (ms.contains("datasets") && ms["datasets"].is_array())
          for (const json& level : ms["datasets"])
            if (level.contains("path") && level["path"] == array.filename().string()) {
              multiscale = &ms;
              if (level.contains("coordinateTransformations")) level_transforms = &level["coordinateTransformations"];
            }
      }
    }
    array_ = array.string();
    listing_.emplace(array_, folder);
    parse_zarray(read_json((array / ".zarray").string(), folder));

    // Spacing and origin of the last three axes from the OME transforms.
    std::vector<double> scale(shape_.size(), 1.0), shift(shape_.size(), 0.0);
    if (level_transforms) apply_transforms(*level_transforms, scale, shift, folder);
    if (multiscale && multiscale->contains("coordinateTransformations"))
      apply_transforms((*multiscale)["coordinateTransformations"], scale, shift, folder);
    if (multiscale && multiscale->contains("axes") && (*multiscale)["axes"].is_array()) {
      const json& axes = (*multiscale)["axes"];
      if (axes.size() != shape_.size())
        throw InputError(folder + ": OME axes name " + std::to_string(axes.size()) + " axes, the array has " +
                         std::to_string(shape_.size()));
      for (std::size_t a = shape_.size() - 3; a < shape_.size(); ++a)
        if (axes[a].is_object() && axes[a].contains("type") && axes[a]["type"] != "space")
          throw InputError(folder + ": OME axis " + axes[a].value("name", std::string("?")) +
                           " of the last three is not a space axis");
    }
    const std::size_t n = shape_.size();
    for (int a = 0; a < 3; ++a) {
      head_.spacing[a] = scale[n - 1 - a];
      head_.origin[a] = shift[n - 1 - a];
      if (!(head_.spacing[a] > 0) || !std::isfinite(head_.spacing[a]) || !std::isfinite(head_.origin[a]))
        throw InputError(folder + ": OME scale " + std::to_string(head_.spacing[a]) + " of axis " +
                         std::to_string(n - 1 - a) + " must be a positive finite number");
    }
  }

  [[noreturn]] void fail(const std::string& what) const { throw InputError(folder_ + ": .zarray: " + what); }

  // .zarray: shape and chunks, then how chunks are named, typed,
  // compressed and filled.
  void parse_zarray(const json& z) {
    if (!z.is_object() || z.value("zarr_format", 0) != 2) fail("zarr_format is not 2 (only Zarr v2 is read)");
    parse_shape(z);
    if (z.value("order", std::string("C")) != "C") fail("order is not C (Fortran-order arrays are not read)");
    if (z.contains("filters") && !z["filters"].is_null() && !(z["filters"].is_array() && z["filters"].empty()))
      fail("filters are not supported (" + z["filters"].dump() + ")");
    parse_separator(z);
    const ScalarType type = parse_dtype(z);
    parse_compressor(z);
    const std::size_t n = shape_.size();
    head_.dims = {shape_[n - 1], shape_[n - 2], shape_[n - 3]};
    head_.type = type;
    head_.name = volume_field_name();  // Zarr stores no name for the array
    detail::checked_byte_count(head_.dims, type, folder_);
    size_chunks(type);
    parse_fill_value(z, type);
  }

  // "shape" and "chunks": positive integers, a volume in the last three axes.
  void parse_shape(const json& z) {
    if (!z.contains("shape") || !z["shape"].is_array() || !z.contains("chunks") || !z["chunks"].is_array() ||
        z["shape"].size() != z["chunks"].size())
      fail("shape and chunks must be lists of one length");
    for (std::size_t a = 0; a < z["shape"].size(); ++a) {
      const json &s = z["shape"][a], &c = z["chunks"][a];
      if (!s.is_number_integer() || !c.is_number_integer() || s.get<std::int64_t>() < 1 || c.get<std::int64_t>() < 1)
        fail("shape and chunks must hold positive integers");
      shape_.push_back(s.get<Id>());
      chunks_.push_back(c.get<Id>());
    }
    const std::size_t n = shape_.size();
    if (n < 3) fail(std::to_string(n) + " dimensions (a volume needs 3)");
    for (std::size_t a = 0; a + 3 < n; ++a)
      if (shape_[a] != 1) fail("axis " + std::to_string(a) + " has size " + std::to_string(shape_[a]) +
                               " (only the last three axes may be longer than 1)");
  }

  // The character between a chunk key's indices.
  void parse_separator(const json& z) {
    const std::string sep = z.value("dimension_separator", std::string("."));
    if (sep != "." && sep != "/") fail("dimension_separator '" + sep + "'");
    separator_ = sep[0];
    // zarr's NestedDirectoryStore wrote '/'-separated chunks before the
    // key existed: reading them as '.' would find no chunk and return an
    // array of fill_value.
    std::error_code ec;
    if (!z.contains("dimension_separator") && fs::is_directory(fs::path(array_) / "0", ec)) separator_ = '/';
  }

  // "dtype": a byte order ('<', '>' or '|') and one of numpy's type codes.
  ScalarType parse_dtype(const json& z) {
    static constexpr TypeName kDtypes[] = {
        {"u1", ScalarType::UInt8},  {"i1", ScalarType::Int8},    {"u2", ScalarType::UInt16},
        {"i2", ScalarType::Int16},  {"i4", ScalarType::Int32},   {"f4", ScalarType::Float32},
        {"f8", ScalarType::Float64}, {"u4", ScalarType::UInt32},  {"i8", ScalarType::Int64},
        {"u8", ScalarType::UInt64},
    };
    if (!z.contains("dtype") || !z["dtype"].is_string()) fail("dtype is not a simple type string");
    dtype_ = z["dtype"].get<std::string>();
    const auto type = type_named(dtype_.size() == 3 ? std::string_view(dtype_).substr(1) : "", kDtypes);
    if (!type) fail("dtype '" + dtype_ + "' is not supported (u1 i1 u2 i2 i4 u4 i8 u8 f4 f8)");
    const char order = dtype_.empty() ? '?' : dtype_[0];
    if (order != '<' && order != '>' && order != '|') fail("dtype '" + dtype_ + "' has no byte order");
    swap_ = scalar_size(*type) > 1 && (order == '>') != (std::endian::native == std::endian::big);
    return *type;
  }

  void parse_compressor(const json& z) {
    if (!z.contains("compressor") || z["compressor"].is_null()) return;
    const json& c = z["compressor"];
    const std::string id = c.is_object() ? c.value("id", std::string()) : std::string();
    if (id == "zlib" || id == "gzip") codec_ = Codec::Zlib;
#if defined(KEYMESH_HAVE_BLOSC)
    else if (id == "blosc") codec_ = Codec::Blosc;
#else
    else if (id == "blosc") fail("compressor 'blosc': keymesh was built without blosc (KEYMESH_BLOSC=OFF)");
#endif
    else fail("compressor '" + id + "' is not supported (none, zlib, gzip, blosc)");
  }

  // A chunk's decoded bytes, refused past kMaxChunkBytes.
  void size_chunks(ScalarType type) {
    std::uint64_t elements = 1;
    for (Id c : chunks_) {
      if (elements > kMaxChunkBytes / static_cast<std::uint64_t>(c)) elements = kMaxChunkBytes + 1;
      else elements *= static_cast<std::uint64_t>(c);
    }
    chunk_bytes_ = elements * scalar_size(type);
    if (elements > kMaxChunkBytes || chunk_bytes_ > kMaxChunkBytes)
      throw LimitError(folder_ + ": .zarray: chunks past 1 GiB decoded are not supported");
  }

  // fill_value, stored as the array's type in native byte order.
  void parse_fill_value(const json& z, ScalarType type) {
    fill_.assign(scalar_size(type), std::byte{0});
    if (!z.contains("fill_value") || z["fill_value"].is_null()) return;
    const json& f = z["fill_value"];
    double v = 0;
    if (f.is_number()) v = f.get<double>();
    else if (f == "NaN") v = std::numeric_limits<double>::quiet_NaN();
    else if (f == "Infinity") v = std::numeric_limits<double>::infinity();
    else if (f == "-Infinity") v = -std::numeric_limits<double>::infinity();
    else fail("fill_value " + f.dump() + " is not a number");
    ImageGrid one;
    one.dims = {1, 1, 1};
    one.type = type;
    one.external = fill_.data();
    visit_any_scalars(one, [&](const auto* p) {
      using T = std::remove_cv_t<std::remove_pointer_t<decltype(p)>>;
      T t{};
      if constexpr (std::is_integral_v<T>) {
        // An integer fill value as the integer itself (a 64-bit id is not a double).
        const bool fits = f.is_number_unsigned() ? f.get<std::uint64_t>() <= std::numeric_limits<T>::max()
                          : f.is_number_integer()
                              ? f.get<std::int64_t>() >= static_cast<std::int64_t>(std::numeric_limits<T>::min()) &&
                                    (f.get<std::int64_t>() < 0 ||
                                     static_cast<std::uint64_t>(f.get<std::int64_t>()) <= std::numeric_limits<T>::max())
                              : v >= static_cast<double>(std::numeric_limits<T>::min()) &&
                                    v <= static_cast<double>(std::numeric_limits<T>::max()) &&
                                    (sizeof(T) < 8 || v < static_cast<double>(std::numeric_limits<T>::max())) &&
                                    v == std::floor(v);
        if (!fits) fail("fill_value " + f.dump() + " does not fit dtype '" + dtype_ + "'");
        t = f.is_number_unsigned() ? static_cast<T>(f.get<std::uint64_t>())
            : f.is_number_integer() ? static_cast<T>(f.get<std::int64_t>())
                                    : static_cast<T>(v);
      } else {
        t = static_cast<T>(v);
      }
      std::memcpy(fill_.data(), &t, sizeof t);
      return 0;
    });
    if (swap_) std::reverse(fill_.begin(), fill_.end());  // read_planes swaps every sample back
  }

  // A listed chunk's bytes. A listed name that cannot be read (a link loop,
  // a dangling link, a directory) is refused naming the chunk: only an
  // absent chunk holds fill_value.
  template <class Bad>
  mesh_bytes::FileBytes read_chunk_file(const std::string& key, const Bad& bad) const {
    const std::string file = (fs::path(array_) / key).string();
    try {
      return mesh_bytes::read_whole_file(file);
    } catch (const InputError& e) {
      const std::string what = e.what();
      throw bad(what.rfind(file + ": ", 0) == 0 ? what.substr(file.size() + 2) : what);
    }
  }

  // The chunk (z, y, x) of the last three axes (index 0 on the others),
  // decoded into `out` (resized to chunk_bytes_); false, `out` untouched,
  // when its file is absent (the chunk holds fill_value). The chunk's bytes
  // on disk must be able to hold it before `out` is sized: a file of a few
  // bytes cannot make the reader allocate a chunk of a gigabyte.
  bool decode_chunk(std::array<Id, 3> index, std::vector<std::byte>& out) {
    std::string key;
    for (std::size_t a = 0; a + 3 < shape_.size(); ++a) key += std::string("0") + separator_;
    key += std::to_string(index[0]) + separator_ + std::to_string(index[1]) + separator_ + std::to_string(index[2]);
    if (!listing_->present(key, separator_)) return false;
    auto bad = [&](const std::string& what) { return InputError(folder_ + ": chunk " + key + ": " + what); };
    const mesh_bytes::FileBytes data = read_chunk_file(key, bad);
    switch (codec_) {
      case Codec::None:
        if (data.size() != chunk_bytes_)
          throw bad("holds " + std::to_string(data.size()) + " bytes, the chunk shape needs " +
                    std::to_string(chunk_bytes_));
        out.resize(chunk_bytes_);
        std::memcpy(out.data(), data.data(), out.size());
        return true;
      case Codec::Zlib: {
        // zlib cannot expand more than ~1032:1 (as the NIfTI and NRRD readers assume).
        if (chunk_bytes_ / 1032 > data.size() + 64)
          throw bad(std::to_string(data.size()) + " bytes of zlib/gzip data cannot inflate to the " +
                    std::to_string(chunk_bytes_) + " bytes the chunk shape needs");
        out.resize(chunk_bytes_);
        if (data.size() <= std::numeric_limits<uInt>::max() &&
            detail::inflate_zlib_or_gzip_exact(data.data(), data.size(), reinterpret_cast<char*>(out.data()), out.size()))
          return true;
        // Otherwise zlib decides, and words the refusal.
        z_stream s{};
        if (inflateInit2(&s, 15 + 32) != Z_OK) throw bad("zlib cannot start");  // 32: zlib or gzip header
        s.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
        s.avail_in = static_cast<uInt>(data.size());
        s.next_out = reinterpret_cast<Bytef*>(out.data());
        s.avail_out = static_cast<uInt>(out.size());
        const int rc = inflate(&s, Z_FINISH);
        const std::uint64_t got = s.total_out;
        inflateEnd(&s);
        if (data.size() > std::numeric_limits<uInt>::max() || rc != Z_STREAM_END || got != out.size())
          throw bad(rc == Z_STREAM_END || rc == Z_BUF_ERROR
                        ? "inflates to " + std::string(rc == Z_BUF_ERROR && got == out.size() ? "more than " : "") +
                              std::to_string(got) + " bytes, the chunk shape needs " + std::to_string(out.size())
                        : "corrupt zlib/gzip data");
        return true;
      }
      case Codec::Blosc: {
#if !defined(KEYMESH_HAVE_BLOSC)
        throw bad("blosc data in a build without blosc");  // not reached: parse_compressor refuses blosc
#else
        std::size_t nbytes = 0;
        if (blosc_cbuffer_validate(data.data(), data.size(), &nbytes) != 0) throw bad("corrupt blosc data");
        if (nbytes != chunk_bytes_)
          throw bad("blosc data holds " + std::to_string(nbytes) + " bytes, the chunk shape needs " +
                    std::to_string(chunk_bytes_));
        out.resize(chunk_bytes_);
        if (blosc_decompress_ctx(data.data(), out.data(), out.size(), 1) != static_cast<int>(out.size()))
          throw bad("corrupt blosc data");
        return true;
#endif
      }
    }
    return false;  // not reached: every codec returns
  }

  std::string folder_, array_;
  std::string dtype_;  // as .zarray spells it, for messages
  std::vector<Id> shape_, chunks_;
  char separator_ = '.';
  Codec codec_ = Codec::None;
  bool swap_ = false;
  std::uint64_t chunk_bytes_ = 0;
  std::vector<std::byte> fill_;
  std::optional<ZarrChunkListing> listing_;  // set once the array's folder is known
  ImageGrid head_;
};

}  // namespace

bool is_zarr_folder(const std::string& folder) {
  const fs::path p(folder);
  std::string name = p.filename().empty() ? p.parent_path().filename().string() : p.filename().string();
  std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return std::tolower(c); });
  return path_exists(p / ".zarray") || path_exists(p / ".zattrs") || path_exists(p / ".zgroup") ||
         (name.size() > 5 && name.compare(name.size() - 5, 5, ".zarr") == 0);
}

std::unique_ptr<PlaneSource> open_zarr(const std::string& folder) {
  return std::make_unique<ZarrPlanes>(folder);
}

}  // namespace keymesh::io
