// The GDCM module (gdcm_api.hpp): the only code of keymesh that calls GDCM,
// built as the shared module libkeymesh_gdcm.so that the DICOM reader opens
// on first use. Runs in the reader's child processes (io/child_process.hpp:
// Debian's GDCM asserts on malformed headers).
#include "gdcm_api.hpp"

#include <gdcmImage.h>
#include <gdcmImageReader.h>
#include <gdcmScanner.h>
#include <gdcmTrace.h>

#include <iostream>
#include <sstream>
#include <string>

namespace {

gdcm::Tag tag_of(KeymeshGdcmTag t) {
  return gdcm::Tag(static_cast<std::uint16_t>(t >> 16), static_cast<std::uint16_t>(t & 0xffffu));
}

void quiet() {
  gdcm::Trace::WarningOff();
  gdcm::Trace::ErrorOff();
  gdcm::Trace::DebugOff();
}

int scan(const char* file, const KeymeshGdcmTag* tags, std::size_t count, KeymeshGdcmTagValue found, void* context) {
  gdcm::Scanner scanner;
  for (std::size_t k = 0; k < count; ++k) scanner.AddTag(tag_of(tags[k]));
  if (!scanner.Scan({file})) return -1;
  for (std::size_t k = 0; k < count; ++k)
    if (const char* v = scanner.GetValue(file, tag_of(tags[k]))) found(context, k, v);
  return scanner.IsKey(file) ? 1 : 0;
}

int decode(const char* file, KeymeshGdcmImage* image, void* out, std::size_t out_bytes) {
  gdcm::ImageReader reader;
  reader.SetFileName(file);
  // GDCM reads a file cut inside its pixel data without failing and
  // only warns; the warning is caught so that no slice of garbage passes.
  std::ostringstream warnings;
  gdcm::Trace::SetWarningStream(warnings);
  gdcm::Trace::WarningOn();
  const bool read = reader.Read();
  gdcm::Trace::WarningOff();
  gdcm::Trace::SetWarningStream(std::cerr);
  if (!read) return kKeymeshGdcmUnreadable;
  if (warnings.str().find("Incomplete Pixel Data") != std::string::npos) return kKeymeshGdcmTruncated;
  const gdcm::Image& img = reader.GetImage();
  const gdcm::PixelFormat& pf = img.GetPixelFormat();
  image->columns = img.GetColumns();
  image->rows = img.GetRows();
  image->samples_per_pixel = pf.GetSamplesPerPixel();
  image->bits_allocated = pf.GetBitsAllocated();
  image->buffer_bytes = img.GetBufferLength();
  const gdcm::DataElement& pixels = img.GetDataElement();
  image->native = pixels.GetSequenceOfFragments() == nullptr;
  if (const gdcm::ByteValue* stored = pixels.GetByteValue()) image->stored_bytes = stored->GetLength();
  if (image->buffer_bytes != out_bytes) return kKeymeshGdcmOtherSize;
  return img.GetBuffer(static_cast<char*>(out)) ? kKeymeshGdcmDecoded : kKeymeshGdcmUndecodable;
}

constexpr KeymeshGdcmApi kApi{kKeymeshGdcmApiVersion, &quiet, &scan, &decode};

}  // namespace

extern "C" __attribute__((visibility("default"))) const KeymeshGdcmApi* keymesh_gdcm_api() { return &kApi; }
