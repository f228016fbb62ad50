#pragma once
// What the GDCM module (libkeymesh_gdcm.so, built from gdcm_module.cpp
// beside this header) hands the DICOM reader (src/io/dicom.cpp): a table of
// C functions over plain types. GDCM's static initialiser loads its
// dictionaries (about 60 M instructions, and 20 shared libraries to map and
// relocate) at every start of any program that links it; in a module opened
// on the first DICOM read (gdcm_library.hpp), only a DICOM read pays it.
// The module links GDCM and nothing of keymesh: it reports by return value
// and the reader words every error. What GDCM throws (std::bad_alloc past
// the child's memory budget, gdcm::Exception) passes through to the reader
// as it did when GDCM was linked in: both sides share libstdc++.
#include <cstddef>
#include <cstdint>

extern "C" {

// Bumped with every change of this file: a module of another keymesh build
// is refused by name rather than called through a table of another shape.
inline constexpr std::uint32_t kKeymeshGdcmApiVersion = 2;

// A DICOM tag as (group << 16) | element.
using KeymeshGdcmTag = std::uint32_t;

// Receives the value of `tags[index]` of a scanned file (called only for
// tags present in it); `value` lives only until the scan returns.
using KeymeshGdcmTagValue = void (*)(void* context, std::size_t index, const char* value);

// What GDCM's ImageReader found in a slice.
struct KeymeshGdcmImage {
  unsigned columns = 0, rows = 0, samples_per_pixel = 0, bits_allocated = 0;
  std::size_t buffer_bytes = 0;  // the decoded pixel data's length
  // Whether the PixelData element is stored uncompressed (native, not
  // encapsulated fragments, whose codec checks their length), and the
  // bytes it then holds. GDCM's buffer_bytes is what the header declares
  // (rows x columns x samples x bits); of a shorter element GDCM copies
  // what there is and leaves the rest of the plane as it was (zeros), so
  // the reader compares the two.
  unsigned native = 0;
  std::size_t stored_bytes = 0;
};

enum KeymeshGdcmDecoded : int {
  kKeymeshGdcmDecoded = 0,         // `out` holds the pixel data
  kKeymeshGdcmUnreadable = 1,      // ImageReader::Read failed
  kKeymeshGdcmTruncated = 2,       // read, but GDCM warned "Incomplete Pixel Data"
  kKeymeshGdcmOtherSize = 3,       // read; buffer_bytes differs from out_bytes: `out` untouched
  kKeymeshGdcmUndecodable = 4,     // read; Image::GetBuffer failed
};

struct KeymeshGdcmApi {
  std::uint32_t version;  // kKeymeshGdcmApiVersion of the module's build
  // Turns GDCM's warnings, errors and debug messages on stderr off.
  void (*quiet)();
  // Scans `file` for `count` tags with gdcm::Scanner, reporting each present
  // tag's value to `found`: -1 when the scan failed, else 1 when the file is
  // DICOM and 0 when not.
  int (*scan)(const char* file, const KeymeshGdcmTag* tags, std::size_t count, KeymeshGdcmTagValue found,
              void* context);
  // Reads one slice with gdcm::ImageReader and fills `image`; decodes its
  // pixel data into `out` when its length is `out_bytes` (KeymeshGdcmDecoded).
  int (*decode)(const char* file, KeymeshGdcmImage* image, void* out, std::size_t out_bytes);
};

// The module's one exported entry point.
const KeymeshGdcmApi* keymesh_gdcm_api();
inline constexpr const char* kKeymeshGdcmEntry = "keymesh_gdcm_api";

}  // extern "C"
