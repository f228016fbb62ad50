#include "dicom.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iterator>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "keymesh/core/error.hpp"
#include "child_process.hpp"
#include "gdcm_module/gdcm_api.hpp"
#include "keymesh/core/loadable_module.hpp"
#include "keymesh/io/input_file.hpp"
#include "volume_formats.hpp"

namespace keymesh::io {

namespace {

// GDCM, through keymesh's module (gdcm_module/gdcm_api.hpp), opened by the
// first DICOM read: before any fork, so that every child process inherits it.
const KeymeshGdcmApi& gdcm() {
#if defined(KEYMESH_GDCM_MODULE_FILE)
  static const KeymeshGdcmApi* const api = [] {
    const auto& table = loadable_module_table<KeymeshGdcmApi>(KEYMESH_GDCM_MODULE_FILE, kKeymeshGdcmEntry,
                                                              kKeymeshGdcmApiVersion, "reading a DICOM series");
    table.quiet();  // GDCM prints its own warnings on stderr; keymesh reports what matters
    return &table;
  }();
  return *api;
#else  // a build without GDCM (KEYMESH_GDCM=OFF, as the GPU check's): no module to open
  throw InputError("reading a DICOM series: keymesh was built without GDCM (KEYMESH_GDCM=OFF)");
#endif
}

constexpr KeymeshGdcmTag tag(std::uint16_t group, std::uint16_t element) {
  return (KeymeshGdcmTag{group} << 16) | element;
}
constexpr KeymeshGdcmTag kSeriesUid = tag(0x0020, 0x000e), kPosition = tag(0x0020, 0x0032),
                         kOrientation = tag(0x0020, 0x0037), kPixelSpacing = tag(0x0028, 0x0030),
                         kRows = tag(0x0028, 0x0010), kColumns = tag(0x0028, 0x0011), kSamples = tag(0x0028, 0x0002),
                         kBitsAllocated = tag(0x0028, 0x0100), kSigned = tag(0x0028, 0x0103),
                         kFrames = tag(0x0028, 0x0008), kSlope = tag(0x0028, 0x1053), kIntercept = tag(0x0028, 0x1052);
// Every tag the scan reads.
constexpr KeymeshGdcmTag kScanTags[] = {kSeriesUid, kPosition, kOrientation, kPixelSpacing, kRows, kColumns,
                               kSamples, kBitsAllocated, kSigned, kFrames, kSlope, kIntercept};
constexpr std::size_t kScanTagCount = std::size(kScanTags);

// A decimal-string (DS/IS) value of `count` numbers separated by '\'; empty
// when absent or malformed (the callers say which).
std::optional<std::vector<double>> numbers(const char* text, std::size_t count) {
  if (!text) return std::nullopt;
  std::vector<double> out;
  const char* p = text;
  while (out.size() < count) {
    char* end = nullptr;
    const double v = std::strtod(p, &end);
    if (end == p || !std::isfinite(v)) return std::nullopt;
    out.push_back(v);
    while (*end == ' ') ++end;
    if (*end == '\\') ++end;
    else if (out.size() < count) return std::nullopt;
    p = end;
  }
  while (*p == ' ') ++p;
  if (*p != '\0') return std::nullopt;
  return out;
}

// One slice's header, as the scanner read it.
struct Slice {
  std::string file;
  std::string series;
  std::array<double, 3> position{0, 0, 0};
  double along_normal = 0;
  double slope = 1, intercept = 0;
};

std::string name_of(const std::string& file) { return std::filesystem::path(file).filename().string(); }

// The slice files of a folder, sorted by name: every file but hidden ones
// and DICOMDIR (subfolders are passed over).
std::vector<std::string> list_slice_files(const std::string& folder) {
  std::vector<std::string> files;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.empty() || name[0] == '.' || name == "DICOMDIR" || entry.is_directory(ec)) continue;
    input_size(entry.path().string());  // as every input: a FIFO or a device is refused by name
    files.push_back(entry.path().string());
  }
  if (ec) throw InputError(folder + ": cannot list the folder: " + ec.message());
  if (files.empty()) throw InputError(folder + ": folder holds no file (expected the DICOM slices of one series)");
  std::sort(files.begin(), files.end());
  return files;
}

// What the first slice sets and every other slice must match.
struct SeriesFormat {
  long rows = 0, columns = 0, bits = 0, is_signed = 0;
  std::string orientation, spacing;  // as the first file spells them ("" when absent)
};

// One file's tags as GDCM's scanner read them (kScanTags order); none when
// the file is no DICOM file.
struct ScannedTags {
  bool dicom = false;
  std::array<std::optional<std::string>, kScanTagCount> values;
};

// What GDCM may allocate for a file in its child process (run_in_child's
// budget): far more than any well-formed slice needs (its bytes, the
// decoded plane, the codec's buffers), far less than a length field can
// declare (4 GiB).
std::size_t gdcm_memory_budget(const std::string& file, std::size_t plane_bytes) {
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(file, ec);
  return (std::size_t{256} << 20) + 4 * (ec ? 0 : static_cast<std::size_t>(size)) + 4 * plane_bytes;
}

// The scanner's reading of one file, in a child process (io/child_process.hpp:
// GDCM asserts on malformed headers), passed back as bytes: a DICOM flag,
// then per tag a presence flag, a 4-byte length and the value.
ScannedTags scan_file(const std::string& folder, const std::string& file) {
  const KeymeshGdcmApi& library = gdcm();
  const std::string bytes = run_in_child(
      [&] {
        // The values live as long as the module's scanner: copied as found.
        std::array<std::optional<std::string>, kScanTagCount> found;
        auto keep = [](void* values, std::size_t k, const char* v) {
          (*static_cast<std::array<std::optional<std::string>, kScanTagCount>*>(values))[k] = v;
        };
        const int dicom = library.scan(file.c_str(), kScanTags, kScanTagCount, keep, &found);
        if (dicom < 0) throw InputError(folder + ": cannot scan the DICOM files");
        std::string out(1, dicom ? '\1' : '\0');
        for (const std::optional<std::string>& v : found) {
          const std::uint32_t size = v ? static_cast<std::uint32_t>(v->size()) : 0;
          out.push_back(v ? '\1' : '\0');
          out.append(reinterpret_cast<const char*>(&size), sizeof size);
          if (v) out.append(*v);
        }
        return out;
      },
      folder + ": " + name_of(file) + ": GDCM", gdcm_memory_budget(file, 0));
  ScannedTags tags;
  std::size_t at = 1;
  tags.dicom = !bytes.empty() && bytes[0] == '\1';
  for (auto& value : tags.values) {
    std::uint32_t size = 0;
    std::memcpy(&size, bytes.data() + at + 1, sizeof size);
    if (bytes[at] == '\1') value = bytes.substr(at + 1 + sizeof size, size);
    at += 1 + sizeof size + size;
  }
  return tags;
}

// The tags of every file as GDCM's scanner read them, and errors that name
// the folder and the file.
class SeriesScan {
 public:
  SeriesScan(const std::string& folder, const std::vector<std::string>& files) : folder_(folder) {
    for (const std::string& f : files) tags_[f] = scan_file(folder, f);
  }

  InputError fail(const std::string& file, const std::string& what) const {
    return InputError(folder_ + ": " + name_of(file) + ": " + what);
  }
  const char* value(const std::string& file, KeymeshGdcmTag t) const {
    const auto it = tags_.find(file);
    if (it == tags_.end()) return nullptr;
    for (std::size_t k = 0; k < kScanTagCount; ++k)
      if (kScanTags[k] == t) return it->second.values[k] ? it->second.values[k]->c_str() : nullptr;
    return nullptr;
  }
  // An integer tag; `fallback` when absent (an error when fallback < 0).
  // Within 32 bits, as DICOM's IS and US values are: "1e300" passes
  // strtod and floor, and its cast to long would be undefined (UBSan).
  long integer(const std::string& file, KeymeshGdcmTag t, const char* what, long fallback) const {
    const char* v = value(file, t);
    if (!v) {
      if (fallback >= 0) return fallback;
      throw fail(file, std::string("no ") + what);
    }
    auto n = numbers(v, 1);
    if (!n || (*n)[0] != std::floor((*n)[0]) || std::abs((*n)[0]) > 4294967295.0)
      throw fail(file, std::string("bad ") + what + " '" + v + "'");
    return static_cast<long>((*n)[0]);
  }

  // One file's slice header. The first file (`first`) sets `format`; every
  // other must match it and the first slice `ref`.
  Slice slice(const std::string& f, bool first, SeriesFormat& format, const Slice* ref, std::size_t files) const {
    if (!tags_.at(f).dicom) throw fail(f, "not a DICOM file (every file of the folder must be a slice)");
    const long samples = integer(f, kSamples, "SamplesPerPixel", 1);
    if (samples != 1) throw fail(f, "SamplesPerPixel " + std::to_string(samples) + " (only one-sample grey images)");
    if (integer(f, kFrames, "NumberOfFrames", 1) != 1)
      throw fail(f, "a multi-frame image (only folders of single-frame slices are read)");
    SeriesFormat mine;
    mine.rows = integer(f, kRows, "Rows", -1);
    mine.columns = integer(f, kColumns, "Columns", -1);
    mine.bits = integer(f, kBitsAllocated, "BitsAllocated", -1);
    mine.is_signed = integer(f, kSigned, "PixelRepresentation", 0);
    const char* uid = value(f, kSeriesUid);
    Slice slice{f, uid ? uid : "", {0, 0, 0}, 0, 1, 0};
    if (first) {
      const char* orient = value(f, kOrientation);
      const char* spacing = value(f, kPixelSpacing);
      mine.orientation = orient ? orient : "";
      mine.spacing = spacing ? spacing : "";
      format = mine;
      if (mine.rows < 1 || mine.columns < 1)
        throw fail(f, "image of " + std::to_string(mine.rows) + " rows and " + std::to_string(mine.columns) + " columns");
    } else {
      check_same_series(f, slice, *ref, mine, format);
    }
    read_placement(f, slice, files);
    return slice;
  }

 private:
  // A slice of another series, size, pixel format, orientation or pixel
  // spacing than the first file (named by `ref`) is refused.
  void check_same_series(const std::string& f, const Slice& slice, const Slice& ref, const SeriesFormat& mine,
                         const SeriesFormat& format) const {
    const std::string first = name_of(ref.file);
    if (slice.series != ref.series)
      throw fail(f, "SeriesInstanceUID " + slice.series + " differs from " + first + "'s " + ref.series +
                        " (a mixed series: keep one series per folder)");
    if (mine.rows != format.rows || mine.columns != format.columns)
      throw fail(f, std::to_string(mine.columns) + " x " + std::to_string(mine.rows) + " pixels, " + first + " has " +
                        std::to_string(format.columns) + " x " + std::to_string(format.rows) + " (a mixed series)");
    if (mine.bits != format.bits || mine.is_signed != format.is_signed)
      throw fail(f, "pixel format differs from " + first + "'s (BitsAllocated / PixelRepresentation)");
    const char* orient = value(f, kOrientation);
    auto a = numbers(orient, 6), o = numbers(format.orientation.c_str(), 6);
    bool same = a.has_value() == o.has_value();
    for (int k = 0; same && a && k < 6; ++k) same = std::abs((*a)[k] - (*o)[k]) <= 1e-4;
    if (!same)
      throw fail(f, "ImageOrientationPatient '" + std::string(orient ? orient : "") + "' differs from " + first +
                        "'s '" + format.orientation + "' (a mixed series)");
    const char* spacing = value(f, kPixelSpacing);
    auto p = numbers(spacing, 2), q = numbers(format.spacing.c_str(), 2);
    same = p.has_value() == q.has_value();
    for (int k = 0; same && p && k < 2; ++k) same = std::abs((*p)[k] - (*q)[k]) <= 1e-6 * std::abs((*q)[k]);
    if (!same)
      throw fail(f, "PixelSpacing '" + std::string(spacing ? spacing : "") + "' differs from " + first + "'s '" +
                        format.spacing + "' (a mixed series)");
  }

  // ImagePositionPatient (needed to order more than one slice), RescaleSlope
  // and RescaleIntercept.
  void read_placement(const std::string& f, Slice& slice, std::size_t files) const {
    if (const char* pos = value(f, kPosition)) {
      auto p = numbers(pos, 3);
      if (!p) throw fail(f, std::string("bad ImagePositionPatient '") + pos + "'");
      // A grid's coordinates are float32: a slice at z = 1e300 is refused
      // here, by name, before its distance to the others is measured.
      for (int a = 0; a < 3; ++a)
        if (!(std::abs((*p)[a]) <= std::numeric_limits<float>::max()))
          throw fail(f, std::string("ImagePositionPatient '") + pos + "': " + "xyz"[a] + " lies past float32's range");
      slice.position = {(*p)[0], (*p)[1], (*p)[2]};
    } else if (files > 1) {
      throw fail(f, "no ImagePositionPatient: the slices cannot be ordered");
    }
    if (const char* v = value(f, kSlope)) {
      auto n = numbers(v, 1);
      if (!n || (*n)[0] == 0) throw fail(f, std::string("bad RescaleSlope '") + v + "'");
      slice.slope = (*n)[0];
    }
    if (const char* v = value(f, kIntercept)) {
      auto n = numbers(v, 1);
      if (!n) throw fail(f, std::string("bad RescaleIntercept '") + v + "'");
      slice.intercept = (*n)[0];
    }
  }

  std::string folder_;
  std::map<std::string, ScannedTags> tags_;
};

// The slices' normal: the cross product of the orientation's row and column
// directions (z when the series has one slice and no orientation).
std::array<double, 3> slice_normal(const SeriesScan& scan, const std::string& first, const std::string& orientation,
                                   std::size_t files) {
  std::array<double, 3> normal{0, 0, 1};
  if (!orientation.empty()) {
    auto o = numbers(orientation.c_str(), 6);
    if (!o) throw scan.fail(first, "bad ImageOrientationPatient '" + orientation + "'");
    const double* r = o->data();
    const double* c = o->data() + 3;
    normal = {r[1] * c[2] - r[2] * c[1], r[2] * c[0] - r[0] * c[2], r[0] * c[1] - r[1] * c[0]};
    const double len = std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    if (!(len > 0.5)) throw scan.fail(first, "ImageOrientationPatient '" + orientation + "' has parallel axes");
    for (double& x : normal) x /= len;
  } else if (files > 1) {
    throw scan.fail(first, "no ImageOrientationPatient: the slices cannot be ordered");
  }
  return normal;
}

// Sorts the slices along the normal; returns their step, refusing repeated
// positions and uneven gaps (a missing slice).
double order_slices(std::vector<Slice>& slices, const std::array<double, 3>& normal, const std::string& folder) {
  for (Slice& s : slices)
    s.along_normal = s.position[0] * normal[0] + s.position[1] * normal[1] + s.position[2] * normal[2];
  std::stable_sort(slices.begin(), slices.end(),
                   [](const Slice& a, const Slice& b) { return a.along_normal < b.along_normal; });
  const std::size_t n = slices.size();
  if (n <= 1) return 1;
  const double step = (slices.back().along_normal - slices.front().along_normal) / static_cast<double>(n - 1);
  // The gap furthest from the mean step names where a slice is missing.
  std::size_t worst = 1;
  auto gap = [&](std::size_t k) { return slices[k].along_normal - slices[k - 1].along_normal; };
  for (std::size_t k = 1; k < n; ++k) {
    // Equal within the decimal strings' rounding, relative to the positions
    // themselves (not to the mean step: one slice far off the others makes
    // that step huge, and then the others' gaps are uneven, not repeated).
    const double scale = std::max({1.0, std::abs(slices[k].along_normal), std::abs(slices[k - 1].along_normal)});
    if (gap(k) <= 1e-6 * scale)
      throw InputError(folder + ": " + name_of(slices[k - 1].file) + " and " + name_of(slices[k].file) +
                       " lie at the same position (two series, or a repeated slice)");
    if (std::abs(gap(k) - step) > std::abs(gap(worst) - step)) worst = k;
  }
  if (std::abs(gap(worst) - step) > 1e-3 * step)
    throw InputError(folder + ": uneven slice spacing: " + name_of(slices[worst - 1].file) + " to " +
                     name_of(slices[worst].file) + " is " + std::to_string(gap(worst)) +
                     " mm, the series averages " + std::to_string(step) + " mm (missing slices?)");
  return step;
}

class DicomPlanes : public PlaneSource {
 public:
  explicit DicomPlanes(const std::string& folder) : folder_(folder) {
    const std::vector<std::string> files = list_slice_files(folder);
    const SeriesScan scan(folder, files);
    const std::string& first = files.front();
    SeriesFormat format;
    for (const std::string& f : files)
      slices_.push_back(scan.slice(f, f == first, format, slices_.empty() ? nullptr : &slices_.front(), files.size()));
    const double step = order_slices(slices_, slice_normal(scan, first, format.orientation, files.size()), folder);

    std::array<double, 2> pixel{1, 1};  // rows apart (y), columns apart (x)
    if (!format.spacing.empty()) {
      auto p = numbers(format.spacing.c_str(), 2);
      if (!p || !((*p)[0] > 0) || !((*p)[1] > 0)) throw scan.fail(first, "bad PixelSpacing '" + format.spacing + "'");
      if (std::max((*p)[0], (*p)[1]) > std::numeric_limits<float>::max())
        throw scan.fail(first, "PixelSpacing '" + format.spacing + "' lies past float32's range");
      pixel = {(*p)[0], (*p)[1]};
    }
    const long bits = format.bits;
    const bool is_signed = format.is_signed != 0;
    if (bits == 8) stored_ = is_signed ? ScalarType::Int8 : ScalarType::UInt8;
    else if (bits == 16) stored_ = is_signed ? ScalarType::Int16 : ScalarType::UInt16;
    else if (bits == 32 && is_signed) stored_ = ScalarType::Int32;
    else
      throw scan.fail(first, "BitsAllocated " + std::to_string(bits) + (is_signed ? " signed" : " unsigned") +
                                 " is not supported (8 or 16 bits, or signed 32)");
    for (const Slice& s : slices_) scaled_ = scaled_ || s.slope != 1 || s.intercept != 0;

    head_.dims = {format.columns, format.rows, static_cast<Id>(slices_.size())};
    head_.spacing = {pixel[1], pixel[0], step};
    head_.origin = slices_.front().position;
    head_.type = scaled_ ? detail::scaled_type(stored_) : stored_;
    head_.name = volume_field_name();
    detail::checked_byte_count(head_.dims, head_.type, folder);
  }

  const ImageGrid& header() const override { return head_; }

  void read_planes(Id first, Id count, std::byte* out) override {
    const std::size_t plane = static_cast<std::size_t>(head_.dims[0] * head_.dims[1]);
    gdcm();  // opened here, not in each child
    for (Id k = 0; k < count; ++k) {
      const Slice& s = slices_[static_cast<std::size_t>(first + k)];
      // In a child process: GDCM asserts on some malformed files (io/child_process.hpp).
      const std::string stored = run_in_child([&] { return decode_slice(s); }, folder_ + ": " + name_of(s.file) + ": GDCM",
                                              gdcm_memory_budget(s.file, plane * scalar_size(stored_)));
      if (stored.size() != plane * scalar_size(stored_))
        throw InputError(folder_ + ": " + name_of(s.file) + ": GDCM decoded " + std::to_string(stored.size()) +
                         " bytes, the header declares " + std::to_string(plane * scalar_size(stored_)));
      std::byte* dst = out + static_cast<std::size_t>(k) * plane * scalar_size(head_.type);
      if (scaled_)
        detail::scale_samples(stored_, reinterpret_cast<const std::byte*>(stored.data()), dst, plane, s.slope,
                              s.intercept);
      else
        std::copy_n(reinterpret_cast<const std::byte*>(stored.data()), stored.size(), dst);
    }
  }

 private:
  // One slice's stored samples, decoded by GDCM's ImageReader into a plane
  // of the size the header declares (checked_byte_count bounded it); the
  // module decodes only pixel data of that very length.
  std::string decode_slice(const Slice& s) const {
    const std::size_t bytes = static_cast<std::size_t>(head_.dims[0] * head_.dims[1]) * scalar_size(stored_);
    std::string stored(bytes, '\0');
    KeymeshGdcmImage image;
    const int decoded = gdcm().decode(s.file.c_str(), &image, stored.data(), bytes);
    if (decoded == kKeymeshGdcmUnreadable)
      throw InputError(folder_ + ": " + name_of(s.file) + ": GDCM cannot read its pixel data");
    if (decoded == kKeymeshGdcmTruncated)
      throw InputError(folder_ + ": " + name_of(s.file) + ": pixel data ends early (a truncated file)");
    // GDCM reads a native PixelData element shorter than the plane without
    // a word and zero-fills the rest: [100, 0, 0, ...] from 2 of 60 bytes.
    if (decoded != kKeymeshGdcmUnreadable && image.native && image.stored_bytes < bytes)
      throw InputError(folder_ + ": " + name_of(s.file) + ": PixelData holds " + std::to_string(image.stored_bytes) +
                       " bytes, " + std::to_string(head_.dims[0]) + " columns x " + std::to_string(head_.dims[1]) +
                       " rows x " + std::to_string(scalar_size(stored_)) + " bytes need " + std::to_string(bytes) +
                       " (a short or damaged slice)");
    if (image.columns != head_.dims[0] || image.rows != head_.dims[1] || image.samples_per_pixel != 1 ||
        image.bits_allocated != 8 * scalar_size(stored_) || image.buffer_bytes != bytes)
      throw InputError(folder_ + ": " + name_of(s.file) + ": pixel data of " + std::to_string(image.buffer_bytes) +
                       " bytes, the header declares " + std::to_string(bytes));
    if (decoded != kKeymeshGdcmDecoded)
      throw InputError(folder_ + ": " + name_of(s.file) + ": GDCM cannot decode its pixel data");
    return stored;
  }

  std::string folder_;
  std::vector<Slice> slices_;
  ScalarType stored_ = ScalarType::UInt16;
  bool scaled_ = false;
  ImageGrid head_;
};

}  // namespace

std::unique_ptr<PlaneSource> open_dicom_series(const std::string& folder) {
  return std::make_unique<DicomPlanes>(folder);
}

}  // namespace keymesh::io
