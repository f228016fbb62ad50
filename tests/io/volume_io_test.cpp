// The volume readers and writers (src/io/{raw,nrrd,nifti,den,vti,volume_io}.cpp).
//
// Every file here is built byte by byte in the test from a sample list the
// test chose, so the expected values come from the test, not from the code
// under test: round trips through each writer for each scalar type;
// hand-made NRRD (attached, detached, raw, gzip, big-endian, spacings, space
// directions and origin), NIfTI-1 (.nii, .nii.gz, byte-swapped, scaled,
// every datatype), VolPack .den and VTK XML .vti (ascii, base64, appended
// raw and base64, zlib); then malformed and hostile files, each of which
// must be refused with an InputError (or LimitError) naming the file, before
// anything of the declared size is allocated.
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "keymesh/io/plane_source.hpp"
#include "io/volume_formats.hpp"
#include "keymesh/io/volume_io.hpp"
#include "zlib_bytes.hpp"

namespace keymesh::io {
namespace {

namespace fs = std::filesystem;

// ---- byte building ------------------------------------------------------------

template <class T>
void put(std::string& out, T v, bool big = false) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (big)
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  out.append(reinterpret_cast<const char*>(b), sizeof(T));
}

template <class T>
void put_at(std::string& out, std::size_t offset, T v, bool big = false) {
  std::string tmp;
  put(tmp, v, big);
  out.replace(offset, sizeof(T), tmp);
}

// Plain RFC 4648 base64, written here so the test does not lean on the
// library's encoder.
std::string base64(const std::string& in) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const unsigned v = (unsigned char)in[i] << 16 | (unsigned char)in[i + 1] << 8 | (unsigned char)in[i + 2];
    for (int s = 18; s >= 0; s -= 6) out += k[(v >> s) & 63];
  }
  if (i < in.size()) {
    unsigned v = (unsigned char)in[i] << 16;
    if (i + 1 < in.size()) v |= (unsigned char)in[i + 1] << 8;
    out += k[(v >> 18) & 63];
    out += k[(v >> 12) & 63];
    out += i + 1 < in.size() ? k[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

// ---- the samples every hand-made file holds ----------------------------------

// A 4x3x2 volume (x fastest) whose samples the test knows: value(i) for
// i = x + 4y + 12z, spread over the type's range, extremes included.
constexpr std::array<Id, 3> kDims{4, 3, 2};
constexpr int kCount = 24;

template <class T>
T value(int i) {
  if constexpr (std::is_floating_point_v<T>) {
    return static_cast<T>(i * 1.25 - 7.5);
  } else {
    if (i == 0) return std::numeric_limits<T>::min();
    if (i == kCount - 1) return std::numeric_limits<T>::max();
    return static_cast<T>(std::numeric_limits<T>::min() / 2 + i * 5);
  }
}

template <class T>
std::string sample_bytes(bool big = false) {
  std::string s;
  for (int i = 0; i < kCount; ++i) put<T>(s, value<T>(i), big);
  return s;
}

template <class T>
std::vector<T> samples_of(const ImageGrid& g) {
  EXPECT_EQ(g.bytes.size(), g.num_points() * sizeof(T));
  std::vector<T> v(static_cast<std::size_t>(g.num_points()));
  std::memcpy(v.data(), g.bytes.data(), g.bytes.size());
  return v;
}

template <class T>
void expect_samples(const ImageGrid& g) {
  EXPECT_EQ(g.dims, kDims);
  const auto v = samples_of<T>(g);
  ASSERT_EQ(v.size(), static_cast<std::size_t>(kCount));
  for (int i = 0; i < kCount; ++i) EXPECT_EQ(v[i], value<T>(i)) << "sample " << i;
}

// Calls f(T{}, type) for every ScalarType.
template <class F>
void for_each_type(F&& f) {
  f(std::uint8_t{}, ScalarType::UInt8);
  f(std::int8_t{}, ScalarType::Int8);
  f(std::uint16_t{}, ScalarType::UInt16);
  f(std::int16_t{}, ScalarType::Int16);
  f(std::int32_t{}, ScalarType::Int32);
  f(float{}, ScalarType::Float32);
  f(double{}, ScalarType::Float64);
}

// ---- files ------------------------------------------------------------------

class VolumeIo : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("keymesh-volume-io-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string file(const std::string& name, const std::string& bytes) {
    const std::string p = (dir_ / name).string();
    std::ofstream(p, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return p;
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

// Runs f, which must throw InputError or LimitError whose message names
// `named` (the file) and contains `fragment`; anything else fails (a
// std::bad_alloc would mean the reader allocated what the header declared).
void expect_refused(const std::function<void()>& f, const std::string& named, const std::string& fragment = "") {
  try {
    f();
    ADD_FAILURE() << "no error for " << named;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  } catch (const LimitError& e) {
    EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "unexpected " << typeid(e).name() << ": " << e.what();
  }
}

void expect_refused_read(const std::string& p, const std::string& fragment = "", const RawOptions* raw = nullptr) {
  expect_refused([&] { read_volume(p, raw); }, p, fragment);
}

// Dims whose samples no machine can hold (2^62 points): a reader that
// allocated before checking would throw std::bad_alloc, not InputError.
constexpr Id kHuge = Id{1} << 21;

// ---- round trips through every writer -----------------------------------------

TEST_F(VolumeIo, RoundTripEveryWriterEveryType) {
  for (const std::string ext : {".vti", ".nrrd", ".raw"}) {
    for_each_type([&](auto tag, ScalarType type) {
      using T = decltype(tag);
      SCOPED_TRACE(ext + " " + scalar_type_name(type));
      ImageGrid g;
      g.allocate(kDims, type);
      const std::string bytes = sample_bytes<T>();
      std::memcpy(g.bytes.data(), bytes.data(), bytes.size());
      g.spacing = {0.5, 1.25, 3.0};
      g.origin = {-1.5, 2.0, 1e-3};
      g.name = "density & <co>";
      const std::string p = path(std::string("rt") + scalar_type_name(type) + ext);
      write_volume(g, p);
      RawOptions raw;
      raw.dims = kDims;
      raw.type = type;
      raw.spacing = g.spacing;
      raw.origin = g.origin;
      const ImageGrid r = read_volume(p, ext == ".raw" ? &raw : nullptr);
      EXPECT_EQ(r.type, type);
      expect_samples<T>(r);
      EXPECT_EQ(r.spacing, g.spacing);
      EXPECT_EQ(r.origin, g.origin);
      if (ext == ".vti") {
        EXPECT_EQ(r.name, g.name);
      }
      // No temporary file is left beside the output.
      int files = 0;
      for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir_)) ++files;
      EXPECT_EQ(files, 1);
      fs::remove(p);
    });
  }
}

TEST_F(VolumeIo, WriterRefusesUnknownExtensionAndUnwritableDirectory) {
  ImageGrid g;
  g.allocate(kDims, ScalarType::UInt8);
  expect_refused([&] { write_volume(g, path("v.xyz")); }, path("v.xyz"), "cannot write this volume format");
  const std::string missing = path("no/such/dir/v.vti");
  expect_refused([&] { write_volume(g, missing); }, missing, "cannot write");
}

TEST_F(VolumeIo, WritingToADeviceWritesThroughIt) {
  // A device is written in place (never renamed over): /dev/full fails with
  // the reason and stays the device it was.
  if (!fs::is_character_file("/dev/full")) GTEST_SKIP() << "no /dev/full";
  ImageGrid g;
  g.allocate({64, 64, 64}, ScalarType::Float32);
  expect_refused([&] { write_volume(g, "/dev/full"); }, "/dev/full", "cannot write this volume format");
  for (const char* ext : {".vti", ".nrrd", ".raw"}) {
    const std::string dev = path(std::string("dev") + ext);
    fs::create_symlink("/dev/full", dev);
    expect_refused([&] { write_volume(g, dev); }, dev, "No space left on device");
    EXPECT_TRUE(fs::is_character_file("/dev/full"));
    EXPECT_TRUE(fs::is_symlink(dev));
  }
}

// ---- raw ------------------------------------------------------------------------

TEST_F(VolumeIo, RawWithHeaderBytesAndBigEndian) {
  for_each_type([&](auto tag, ScalarType type) {
    using T = decltype(tag);
    SCOPED_TRACE(scalar_type_name(type));
    const std::string p = file("v.raw", "HEADER" + sample_bytes<T>(true) + "trailing bytes are ignored");
    RawOptions o;
    o.dims = kDims;
    o.type = type;
    o.big_endian = true;
    o.header_bytes = 6;
    o.spacing = {1, 2, 3};
    const ImageGrid g = read_volume(p, &o);
    expect_samples<T>(g);
    EXPECT_EQ(g.spacing, (std::array<double, 3>{1, 2, 3}));
  });
}

TEST_F(VolumeIo, RawRefusesBadOptions) {
  const std::string p = file("v.raw", sample_bytes<float>());
  RawOptions o;
  o.dims = kDims;
  EXPECT_NO_THROW(read_volume(p, &o));
  for (Id bad : {Id{0}, Id{-3}}) {
    o.dims = {4, bad, 2};
    expect_refused_read(p, "--dims y", &o);
  }
  o.dims = {kHuge, kHuge, kHuge};  // 2^63 points: overflows
  expect_refused_read(p, "overflow", &o);
  o.dims = {kHuge, kHuge, 4};  // 2^44 points: declared > file
  expect_refused_read(p, "file holds", &o);
  o.dims = {4, 3, 3};  // one slice more than the file holds
  expect_refused_read(p, "expected 144", &o);
  o.dims = kDims;
  o.header_bytes = 1;
  expect_refused_read(p, "header bytes", &o);
  o.header_bytes = -1;
  expect_refused_read(p, "negative", &o);
  o.header_bytes = 0;
  o.spacing = {1, 0, 1};
  expect_refused_read(p, "spacing y", &o);
  o.spacing = {1, 1, std::nan("")};
  expect_refused_read(p, "spacing z", &o);
  o.spacing = {1, 1, 1};
  o.origin = {std::numeric_limits<double>::infinity(), 0, 0};
  expect_refused_read(p, "origin x", &o);
  o.origin = {0, 0, 0};
  expect_refused_read(path("missing.raw"), "no such file", &o);
  expect_refused_read(p, "needs --dims");  // .raw without options
}

// ---- NRRD ----------------------------------------------------------------------

std::string nrrd_header(const std::string& type, const std::string& extra) {
  const std::string fields = extra.empty() || extra.back() == '\n' ? extra : extra + "\n";
  return "NRRD0004\n# made by the test\ntype: " + type + "\ndimension: 3\nsizes: 4 3 2\n" + fields + "\n";
}

TEST_F(VolumeIo, NrrdAttachedRawEveryType) {
  const std::pair<const char*, ScalarType> names[] = {
      {"uchar", ScalarType::UInt8},  {"signed char", ScalarType::Int8}, {"unsigned short", ScalarType::UInt16},
      {"short", ScalarType::Int16},  {"int", ScalarType::Int32},        {"float", ScalarType::Float32},
      {"double", ScalarType::Float64}};
  for (const auto& entry : names) {
    const std::string name = entry.first;  // (clang 14 cannot capture structured bindings)
    const ScalarType type = entry.second;
    SCOPED_TRACE(name);
    for_each_type([&](auto tag, ScalarType t) {
      using T = decltype(tag);
      if (t != type) return;
      for (bool big : {false, true}) {
        const std::string p =
            file("v.nrrd", nrrd_header(name, std::string("encoding: raw\nendian: ") + (big ? "big" : "little") +
                                                 "\nspacings: 0.5 2 -3\n") +
                               sample_bytes<T>(big));
        const ImageGrid g = read_volume(p);
        EXPECT_EQ(g.type, type);
        expect_samples<T>(g);
        EXPECT_EQ(g.spacing, (std::array<double, 3>{0.5, 2, 3}));
      }
    });
  }
}

TEST_F(VolumeIo, NrrdGzipSpaceDirectionsAndOrigin) {
  const std::string p = file(
      "v.nrrd", nrrd_header("uint16", "encoding: gzip\nendian: big\nspace dimension: 3\n"
                                      "space directions: (0,0,2) (0,1.5,0) (3,4,0)\nspace origin: (10,-20,30.5)\n") +
                    gzip_bytes(sample_bytes<std::uint16_t>(true)));
  const ImageGrid g = read_volume(p);
  expect_samples<std::uint16_t>(g);
  EXPECT_EQ(g.spacing, (std::array<double, 3>{2, 1.5, 5}));  // |(3,4,0)| = 5
  EXPECT_EQ(g.origin, (std::array<double, 3>{10, -20, 30.5}));
}

TEST_F(VolumeIo, NrrdDetachedRawAndGzip) {
  file("data.raw", sample_bytes<float>());
  const std::string raw = file("v.nhdr", nrrd_header("float", "encoding: raw\ndata file: data.raw"));
  expect_samples<float>(read_volume(raw));
  file("data.raw.gz", gzip_bytes(sample_bytes<std::int32_t>()));
  const std::string gz = file("g.nhdr", nrrd_header("int32", "encoding: gz\ndatafile: data.raw.gz"));
  expect_samples<std::int32_t>(read_volume(gz));
  // An absolute data file path, a byte skip, no blank line at the end.
  file("skip.raw", "0123456789" + sample_bytes<std::int16_t>());
  const std::string abs = file("a.nhdr", "NRRD0005\ntype: short\ndimension: 3\nsizes: 4 3 2\nencoding: raw\n"
                                         "byte skip: 10\ndata file: " + path("skip.raw"));
  expect_samples<std::int16_t>(read_volume(abs));
  // Line skip then byte skip in the data file.
  file("lines.raw", "first line\nsecond\nXY" + sample_bytes<float>());
  const std::string lines = file("l.nhdr", nrrd_header("float", "encoding: raw\nline skip: 2\nbyte skip: 2\n"
                                                                "data file: lines.raw"));
  expect_samples<float>(read_volume(lines));
  expect_refused_read(file("l2.nhdr", nrrd_header("float", "encoding: raw\nline skip: 3\ndata file: lines.raw")),
                      "line skip");
  expect_refused_read(file("l3.nhdr", nrrd_header("float", "encoding: gzip\nbyte skip: 4\ndata file: lines.raw")),
                      "not supported");
}

TEST_F(VolumeIo, NrrdLeadingScalarAxisAndComments) {
  const std::string p =
      file("v.nrrd", "NRRD0004\r\n# comment\r\ntype: uint8\r\ndimension: 4\r\nsizes: 1 4 3 2\r\nencoding: raw\r\n"
                     "key:=value\r\nspacings: nan 1 2 4\r\n\r\n" + sample_bytes<std::uint8_t>());
  const ImageGrid g = read_volume(p);
  expect_samples<std::uint8_t>(g);
  EXPECT_EQ(g.spacing, (std::array<double, 3>{1, 2, 4}));
}

TEST_F(VolumeIo, NrrdGzipReadsOnlyTheDeclaredSize) {
  // A gzip body that inflates to 64 MiB while the header declares 24 bytes:
  // the reader takes the 24 and inflates nothing more (this returns at once).
  std::string body = sample_bytes<std::uint8_t>() + std::string(64u << 20, '\0');
  const std::string p = file("bomb.nrrd", nrrd_header("uint8", "encoding: gzip") + gzip_bytes(body));
  const ImageGrid g = read_volume(p);
  expect_samples<std::uint8_t>(g);
  EXPECT_EQ(g.bytes.size(), 24u);
}

TEST_F(VolumeIo, NrrdMalformed) {
  const std::string good = sample_bytes<float>();
  expect_refused_read(file("magic.nrrd", "NRRX0004\ntype: float\n\n" + good), "not a NRRD file");
  expect_refused_read(file("empty.nrrd", ""), "not a NRRD file");
  expect_refused_read(file("nofields.nrrd", "NRRD0004\n\n" + good), "lacks type");
  expect_refused_read(file("type.nrrd", nrrd_header("complex", "encoding: raw") + good), "complex");
  expect_refused_read(file("dim.nrrd", "NRRD0004\ntype: float\ndimension: 2\nsizes: 4 3 2\n\n" + good),
                      "dimension 2 but 3 sizes");
  expect_refused_read(file("dim2.nrrd", "NRRD0004\ntype: float\ndimension: 2\nsizes: 4 6\n\n" + good),
                      "only 3D");
  for (const char* sizes : {"4 0 2", "4 -3 2", "4 3 2.5", "4 x 2", "4 3 1e300"})
    expect_refused_read(file("sizes.nrrd", std::string("NRRD0004\ntype: float\ndimension: 3\nsizes: ") + sizes +
                                               "\n\n" + good),
                        "size");
  expect_refused_read(file("endian.nrrd", nrrd_header("float", "endian: middle") + good), "endian");
  expect_refused_read(file("enc.nrrd", nrrd_header("float", "encoding: bzip2") + good), "bzip2");
  expect_refused_read(file("sp.nrrd", nrrd_header("float", "spacings: 1 0 1") + good), "spacing");
  expect_refused_read(file("sp2.nrrd", nrrd_header("float", "spacings: 1 1") + good), "spacings");
  expect_refused_read(file("sd.nrrd", nrrd_header("float", "space directions: (1,0,0) (0,1,0") + good),
                      "space directions");
  expect_refused_read(file("line.nrrd", nrrd_header("float", "no colon here") + good), "malformed");
  expect_refused_read(file("long.nrrd", "NRRD0004\n# " + std::string(100000, 'x') + "\n"), "too long");
  expect_refused_read(file("list.nhdr", nrrd_header("float", "data file: LIST")), "multi-file");
  expect_refused_read(file("nodata.nhdr", nrrd_header("float", "data file: nothing.raw")), "nothing.raw");
  expect_refused_read(file("skip.nrrd", nrrd_header("float", "byte skip: -1") + good), "byte skip");
  // Truncated: one sample short, raw and gzip.
  expect_refused_read(file("short.nrrd", nrrd_header("float", "encoding: raw") + good.substr(4)), "declares 96");
  expect_refused_read(file("shortgz.nrrd", nrrd_header("float", "encoding: gzip") + gzip_bytes(good.substr(4))),
                      "ends after 92 of 96");
  const std::string gz = gzip_bytes(good);
  expect_refused_read(file("cutgz.nrrd", nrrd_header("float", "encoding: gzip") + gz.substr(0, gz.size() / 2)),
                      "gzip");
  expect_refused_read(file("notgz.nrrd", nrrd_header("float", "encoding: gzip") + std::string(200, 'x')), "gzip");
}

TEST_F(VolumeIo, NrrdHugeDeclarationsRefusedBeforeAllocation) {
  const std::string huge = std::to_string(kHuge);
  // 2^63 points overflow; 2^42 points do not but the file holds 24 bytes.
  for (const std::string& sizes : {huge + " " + huge + " " + huge, huge + " " + huge + " 1"}) {
    for (const char* enc : {"raw", "gzip"}) {
      SCOPED_TRACE(sizes + " " + enc);
      const std::string body = std::string(enc) == "raw" ? sample_bytes<float>() : gzip_bytes(sample_bytes<float>());
      expect_refused_read(file("huge.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: " + sizes +
                                                "\nencoding: " + enc + "\n\n" + body));
    }
  }
}

// ---- NIfTI-1 --------------------------------------------------------------------

struct Nifti {
  std::int16_t datatype = 16;
  std::int16_t bitpix = 32;
  std::array<std::int16_t, 8> dim{3, 4, 3, 2, 1, 1, 1, 1};
  std::array<float, 4> pixdim{1, 0.75f, 1.5f, 2.5f};
  float vox_offset = 352;
  float slope = 0, inter = 0;
  const char* magic = "n+1";
  std::int32_t sizeof_hdr = 348;

  std::string header(bool big) const {
    std::string h(348, '\0');
    put_at(h, 0, sizeof_hdr, big);
    for (int i = 0; i < 8; ++i) put_at(h, 40 + 2 * i, dim[i], big);
    put_at(h, 70, datatype, big);
    put_at(h, 72, bitpix, big);
    for (int i = 0; i < 4; ++i) put_at(h, 76 + 4 * i, pixdim[i], big);
    put_at(h, 108, vox_offset, big);
    put_at(h, 112, slope, big);
    put_at(h, 116, inter, big);
    std::memcpy(h.data() + 344, magic, 4);
    return h;
  }
  // Header, the 4-byte extension flag, samples.
  std::string file(bool big, const std::string& samples) const { return header(big) + std::string(4, '\0') + samples; }
};

// NIfTI datatype codes and the scalar types they hold.
const std::pair<std::int16_t, ScalarType> kNiftiTypes[] = {{2, ScalarType::UInt8},    {256, ScalarType::Int8},
                                                          {512, ScalarType::UInt16}, {4, ScalarType::Int16},
                                                          {8, ScalarType::Int32},    {16, ScalarType::Float32},
                                                          {64, ScalarType::Float64}};

// Calls f(code, T{}, type) for every NIfTI datatype code and its sample type T.
template <class F>
void for_each_nifti_type(F&& f) {
  for (const auto& entry : kNiftiTypes) {
    const std::int16_t code = entry.first;
    const ScalarType type = entry.second;
    for_each_type([&](auto tag, ScalarType t) {
      if (t == type) f(code, tag, type);
    });
  }
}

TEST_F(VolumeIo, NiftiEveryDatatypeBothByteOrders) {
  for_each_nifti_type([&](std::int16_t code, auto tag, ScalarType type) {
      using T = decltype(tag);
      for (bool big : {false, true}) {
        SCOPED_TRACE(std::string(scalar_type_name(type)) + (big ? " big" : " little"));
        Nifti n;
        n.datatype = code;
        n.bitpix = static_cast<std::int16_t>(8 * sizeof(T));
        const std::string p = file("v.nii", n.file(big, sample_bytes<T>(big)));
        const ImageGrid g = read_volume(p);
        EXPECT_EQ(g.type, type);
        expect_samples<T>(g);
        EXPECT_EQ(g.spacing, (std::array<double, 3>{0.75, 1.5, 2.5}));
        const std::string gz = file("v.nii.gz", gzip_bytes(n.file(big, sample_bytes<T>(big))));
        expect_samples<T>(read_volume(gz));
      }
  });
}

TEST_F(VolumeIo, NiftiScaleSlopeAndIntercept) {
  Nifti n;
  n.datatype = 4;
  n.bitpix = 16;
  n.slope = 0.5f;
  n.inter = -3;
  n.pixdim = {1, -2, 0, std::nanf("")};  // negative: its size; zero and NaN: 1
  for (bool big : {false, true}) {
    const ImageGrid g = read_volume(file("s.nii.gz", gzip_bytes(n.file(big, sample_bytes<std::int16_t>(big)))));
    ASSERT_EQ(g.type, ScalarType::Float32);
    const auto v = samples_of<float>(g);
    for (int i = 0; i < kCount; ++i) EXPECT_EQ(v[i], static_cast<float>(0.5 * value<std::int16_t>(i) - 3)) << i;
    EXPECT_EQ(g.spacing, (std::array<double, 3>{2, 1, 1}));
  }
  // float64 data stays float64 when scaled.
  n.datatype = 64;
  n.bitpix = 64;
  const ImageGrid d = read_volume(file("d.nii", n.file(false, sample_bytes<double>())));
  ASSERT_EQ(d.type, ScalarType::Float64);
  const auto v = samples_of<double>(d);
  for (int i = 0; i < kCount; ++i) EXPECT_EQ(v[i], 0.5 * value<double>(i) - 3) << i;
  // slope 1, intercept 0 and slope 0 (unset) leave the stored type.
  n.datatype = 2;
  n.bitpix = 8;
  for (float slope : {0.0f, 1.0f}) {
    n.slope = slope;
    n.inter = 0;
    const ImageGrid u = read_volume(file("u.nii", n.file(false, sample_bytes<std::uint8_t>())));
    EXPECT_EQ(u.type, ScalarType::UInt8);
    expect_samples<std::uint8_t>(u);
  }
}

TEST_F(VolumeIo, NiftiExtensionsBeforeTheData) {
  Nifti n;
  n.vox_offset = 352 + 4096 + 16;  // past the 4 flag bytes and an extension
  const std::string p = file("x.nii", n.header(false) + std::string(4 + 4096 + 16, '\x01') + sample_bytes<float>());
  expect_samples<float>(read_volume(p));
}

TEST_F(VolumeIo, NiftiMalformed) {
  const std::string s = sample_bytes<float>();
  Nifti n;
  {
    Nifti m = n;
    m.sizeof_hdr = 540;  // NIfTI-2
    expect_refused_read(file("v2.nii", m.file(false, s)), "sizeof_hdr");
  }
  {
    Nifti m = n;
    m.magic = "ni1";
    expect_refused_read(file("pair.nii", m.file(false, s)), "two-file");
    m.magic = "abc";
    expect_refused_read(file("magic.nii", m.file(false, s)), "bad magic");
  }
  for (std::int16_t d0 : {0, 2, 8, -1}) {
    Nifti m = n;
    m.dim[0] = d0;
    expect_refused_read(file("d0.nii", m.file(false, s)), "dim[0]");
  }
  for (std::int16_t d : {0, -4}) {
    Nifti m = n;
    m.dim[2] = d;
    expect_refused_read(file("d2.nii", m.file(false, s)), "dim[2]");
  }
  {
    Nifti m = n;
    m.dim = {4, 4, 3, 2, 2, 1, 1, 1};  // a time series
    expect_refused_read(file("4d.nii", m.file(false, s + s)), "dim[4] = 2");
  }
  // (768, 1024, 1280: uint32, int64, uint64 label maps, read.)
  for (std::int16_t code : {0, 1, 32, 128, 1536, 1792, 2304}) {
    Nifti m = n;
    m.datatype = code;
    expect_refused_read(file("dt.nii", m.file(false, s)), "datatype " + std::to_string(code));
  }
  for (float off : {0.0f, 100.0f, 352.5f, std::nanf(""), 1e20f}) {
    Nifti m = n;
    m.vox_offset = off;
    expect_refused_read(file("off.nii", m.file(false, s)), "vox_offset");
  }
  expect_refused_read(file("short.nii", n.file(false, s.substr(1))), "file holds 447 bytes");
  expect_refused_read(file("hdr.nii", n.header(false).substr(0, 200)), "truncated");
  expect_refused_read(file("shortgz.nii.gz", gzip_bytes(n.file(false, s.substr(8)))), "ends after 88 of 96");
  expect_refused_read(file("hdrgz.nii.gz", gzip_bytes(n.header(false).substr(0, 100))), "truncated");
  const std::string gz = gzip_bytes(n.file(false, s));
  expect_refused_read(file("cut.nii.gz", gz.substr(0, gz.size() - 30)), "");
  expect_refused_read(file("empty.nii", ""), "");
}

TEST_F(VolumeIo, NiftiHugeDeclarationsRefusedBeforeAllocation) {
  Nifti n;
  n.dim = {3, 32767, 32767, 32767, 1, 1, 1, 1};  // 2^45 points, 2^50 bytes of float64
  n.datatype = 64;
  n.bitpix = 64;
  expect_refused_read(file("huge.nii", n.file(false, sample_bytes<double>())), "file holds");
  expect_refused_read(file("huge.nii.gz", gzip_bytes(n.file(false, sample_bytes<double>()))), "cannot hold");
  // Within zlib's 1032:1 but not backed by data: fails once the stream
  // ends, having allocated only what the stream inflated to.
  n.dim = {3, 1024, 1024, 16, 1, 1, 1, 1};  // 128 MiB declared, 200 kB of incompressible data
  std::string noise(200000, '\0');
  std::uint32_t state = 12345;
  for (char& c : noise) c = static_cast<char>((state = state * 1664525u + 1013904223u) >> 24);
  const std::string lie = gzip_bytes(n.file(false, noise));
  ASSERT_GT(lie.size() * 1032, std::size_t{128} << 20);  // zlib's ratio alone cannot refuse it
  expect_refused_read(file("lie.nii.gz", lie), "ends after 200000 of 134217728");
}

// ---- VolPack .den ----------------------------------------------------------------

std::string den_file(bool big, std::array<std::int16_t, 3> dims, std::int32_t length, const std::string& samples) {
  std::string h(62, '\0');
  put_at<std::int16_t>(h, 0, 1, big);
  for (int a = 0; a < 3; ++a) put_at<std::int16_t>(h, 50 + 2 * a, dims[a], big);
  put_at(h, 58, length, big);
  return h + samples;
}

TEST_F(VolumeIo, DenBothByteOrders) {
  for (bool big : {false, true}) {
    const ImageGrid g = read_volume(file("v.den", den_file(big, {4, 3, 2}, 24, sample_bytes<std::uint8_t>())));
    EXPECT_EQ(g.type, ScalarType::UInt8);
    expect_samples<std::uint8_t>(g);
  }
}

TEST_F(VolumeIo, DenMalformed) {
  const std::string s = sample_bytes<std::uint8_t>();
  std::string bad = den_file(false, {4, 3, 2}, 24, s);
  put_at<std::int16_t>(bad, 0, 7);
  expect_refused_read(file("version.den", bad), "version");
  expect_refused_read(file("len.den", den_file(false, {4, 3, 2}, 25, s)), "inconsistent");
  expect_refused_read(file("neg.den", den_file(false, {4, -3, 2}, -24, s)), "map_len[1]");
  expect_refused_read(file("zero.den", den_file(false, {0, 3, 2}, 0, s)), "map_len[0]");
  expect_refused_read(file("short.den", den_file(false, {4, 3, 2}, 24, s.substr(1))), "file holds 85");
  expect_refused_read(file("hdr.den", std::string(20, '\0')), "62-byte");
  // 32767^2 x 2 = 2^31 samples declared (map_length wraps in int32) over 24 bytes.
  expect_refused_read(file("huge.den", den_file(false, {32767, 32767, 2}, 32767 * 32767 * 2, s)), "");
}

// ---- VTK XML ImageData -----------------------------------------------------------

std::string vti_head(const std::string& root_extra, const std::string& extent = "0 3 0 2 0 1",
                     const std::string& geometry = "Origin=\"1 2 3\" Spacing=\"0.5 1 2\"") {
  return "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\"" + root_extra +
         ">\n <ImageData WholeExtent=\"" + extent + "\" " + geometry + ">\n  <Piece Extent=\"" + extent +
         "\">\n   <PointData Scalars=\"f\">\n";
}
const std::string kVtiTail = "   </PointData>\n  </Piece>\n </ImageData>\n";

template <class T>
std::string vtk_type_name() {
  if constexpr (std::is_same_v<T, std::uint8_t>) return "UInt8";
  if constexpr (std::is_same_v<T, std::int8_t>) return "Int8";
  if constexpr (std::is_same_v<T, std::uint16_t>) return "UInt16";
  if constexpr (std::is_same_v<T, std::int16_t>) return "Int16";
  if constexpr (std::is_same_v<T, std::int32_t>) return "Int32";
  if constexpr (std::is_same_v<T, float>) return "Float32";
  if constexpr (std::is_same_v<T, double>) return "Float64";
}

template <class T>
std::string ascii_samples() {
  std::string s;
  char buf[64];
  for (int i = 0; i < kCount; ++i) {
    if constexpr (std::is_floating_point_v<T>) std::snprintf(buf, sizeof buf, " %.17g", static_cast<double>(value<T>(i)));
    else std::snprintf(buf, sizeof buf, " %lld", static_cast<long long>(value<T>(i)));
    s += buf;
  }
  return s;
}

// One block of VTK's binary layout: a size header, or, compressed, the
// header (blocks, block size, last size, compressed sizes) then the zlib blocks.
std::string vtk_block(const std::string& data, bool header64, bool big, bool compressed, std::size_t block = 40) {
  std::string out;
  auto h = [&](std::uint64_t v) { header64 ? put<std::uint64_t>(out, v, big) : put<std::uint32_t>(out, static_cast<std::uint32_t>(v), big); };
  if (!compressed) {
    h(data.size());
    return out + data;
  }
  std::vector<std::string> parts;
  for (std::size_t at = 0; at < data.size(); at += block) parts.push_back(zlib_bytes(data.substr(at, block)));
  h(parts.size());
  h(block);
  h(data.size() % block);
  for (const auto& p : parts) h(p.size());
  for (const auto& p : parts) out += p;
  return out;
}

TEST_F(VolumeIo, VtiEveryModeEveryType) {
  for_each_type([&](auto tag, ScalarType type) {
    using T = decltype(tag);
    const std::string vt = vtk_type_name<T>();
    const std::string array = "    <DataArray type=\"" + vt + "\" Name=\"f\" NumberOfComponents=\"1\" format=\"";
    auto check = [&](const std::string& what, const std::string& bytes) {
      SCOPED_TRACE(vt + " " + what);
      const ImageGrid g = read_volume(file("v.vti", bytes));
      EXPECT_EQ(g.type, type);
      expect_samples<T>(g);
      EXPECT_EQ(g.spacing, (std::array<double, 3>{0.5, 1, 2}));
      EXPECT_EQ(g.origin, (std::array<double, 3>{1, 2, 3}));
      EXPECT_EQ(g.name, "f");
    };
    check("ascii", vti_head("") + array + "ascii\">" + ascii_samples<T>() + "\n    </DataArray>\n" + kVtiTail +
                       "</VTKFile>\n");
    for (bool big : {false, true})
      for (bool header64 : {false, true})
        for (bool compressed : {false, true}) {
          const std::string root = std::string(" byte_order=\"") + (big ? "BigEndian" : "LittleEndian") +
                                   "\" header_type=\"" + (header64 ? "UInt64" : "UInt32") + "\"" +
                                   (compressed ? " compressor=\"vtkZLibDataCompressor\"" : "");
          const std::string block = vtk_block(sample_bytes<T>(big), header64, big, compressed);
          const std::string mode = std::string(big ? "big" : "little") + (header64 ? " 64" : " 32") +
                                   (compressed ? " zlib" : "");
          // Inline base64: VTK encodes the header and the data as two runs.
          const std::size_t hsize = block.size() - (compressed ? 0 : kCount * sizeof(T));
          const std::string inline_b64 = compressed ? base64(block)
                                                    : base64(block.substr(0, hsize)) + base64(block.substr(hsize));
          check("binary " + mode, vti_head(root) + array + "binary\">\n" + inline_b64 + "\n    </DataArray>\n" +
                                      kVtiTail + "</VTKFile>\n");
          // Appended raw, the array after a dummy block at offset > 0.
          const std::string dummy = vtk_block("xyzw", header64, big, false);
          check("appended raw " + mode,
                vti_head(root) + array + "appended\" offset=\"" + std::to_string(dummy.size()) + "\"/>\n" + kVtiTail +
                    "<AppendedData encoding=\"raw\">\n   _" + dummy + block + "\n</AppendedData>\n</VTKFile>\n");
          check("appended base64 " + mode,
                vti_head(root) + array + "appended\" offset=\"0\"/>\n" + kVtiTail +
                    "<AppendedData encoding=\"base64\">\n   _" + base64(block) + "\n</AppendedData>\n</VTKFile>\n");
        }
  });
}

TEST_F(VolumeIo, VtiExtentNotAtZeroMovesTheOrigin) {
  // Point (i, j, k) lies at Origin + (i, j, k) * Spacing for i, j, k in the
  // extent: the first point of extent "2 5 ..." is at Origin + 2 * Spacing.
  const std::string p = file("e.vti", vti_head("", "2 5 -1 1 10 11") +
                                          "<DataArray type=\"UInt8\" Name=\"f\" format=\"ascii\">" +
                                          ascii_samples<std::uint8_t>() + "</DataArray>" + kVtiTail + "</VTKFile>");
  const ImageGrid g = read_volume(p);
  expect_samples<std::uint8_t>(g);
  EXPECT_EQ(g.origin, (std::array<double, 3>{1 + 2 * 0.5, 2 - 1, 3 + 10 * 2}));
}

TEST_F(VolumeIo, VtiMalformed) {
  const std::string f32 = sample_bytes<float>();
  const std::string arr = "<DataArray type=\"Float32\" Name=\"f\" format=\"";
  auto appended = [&](const std::string& root, const std::string& extent, const std::string& data) {
    return vti_head(root, extent) + arr + "appended\" offset=\"0\"/>" + kVtiTail +
           "<AppendedData encoding=\"raw\">_" + data + "</AppendedData></VTKFile>";
  };
  auto inline_ascii = [&](const std::string& extent, const std::string& values, const std::string& type = "Float32") {
    return vti_head("", extent) + "<DataArray type=\"" + type + "\" Name=\"f\" format=\"ascii\">" + values +
           "</DataArray>" + kVtiTail + "</VTKFile>";
  };
  const std::string ext = "0 3 0 2 0 1";
  expect_refused_read(file("notxml.vti", "hello"), "");
  expect_refused_read(file("root.vti", "<VTKFile type=\"PolyData\"><PolyData/></VTKFile>"), "PolyData");
  expect_refused_read(file("open.vti", vti_head("")), "not closed");
  expect_refused_read(file("noimg.vti", "<VTKFile type=\"ImageData\"></VTKFile>"), "<ImageData>");
  for (const char* e : {"0 3 0 2", "0 3 0 -1 0 1", "0 3 0 2.5 0 1", "0 3 0 x 0 1", "0 1e300 0 1 0 1"})
    expect_refused_read(file("ext.vti", inline_ascii(e, ascii_samples<float>())), "WholeExtent");
  expect_refused_read(file("sp.vti", vti_head("", ext, "Spacing=\"1 0 1\"") + arr + "ascii\">" +
                                         ascii_samples<float>() + "</DataArray>" + kVtiTail + "</VTKFile>"),
                      "Spacing");
  expect_refused_read(file("few.vti", inline_ascii(ext, " 1 2 3")), "holds 3 values, expected 24");
  expect_refused_read(file("nan.vti", inline_ascii(ext, ascii_samples<float>().substr(0, 10) + " nonsense")),
                      "bad number");
  expect_refused_read(file("range.vti", inline_ascii(ext, " 300" + ascii_samples<std::uint8_t>().substr(2), "UInt8")),
                      "does not fit");
  expect_refused_read(file("type.vti", inline_ascii(ext, ascii_samples<float>(), "Float16")), "no supported type");
  // Int64 is read (a label map), but ascii values past 2^53 would not be exact.
  const std::string past_2_53 = " 9007199254740993" + ascii_samples<std::uint8_t>().substr(2);
  expect_refused_read(file("big.vti", inline_ascii(ext, past_2_53, "Int64")), "exactly");
  expect_refused_read(file("comp.vti", vti_head("") + arr + "ascii\" NumberOfComponents=\"3\">1 2 3</DataArray>" +
                                           kVtiTail + "</VTKFile>"),
                      "components");
  expect_refused_read(file("noarr.vti", vti_head("") + kVtiTail + "</VTKFile>"), "no point data array");
  expect_refused_read(file("comp.vti", vti_head("", ext) + arr + "ascii\" NumberOfComponents=\"3\">" +
                                           ascii_samples<float>() + "</DataArray>" + kVtiTail + "</VTKFile>"),
                      "components");
  // Appended raw: size header disagrees, data truncated, offset past the end.
  std::string wrong;
  put<std::uint32_t>(wrong, 92);
  expect_refused_read(file("size.vti", appended("", ext, wrong + f32.substr(4))), "WholeExtent needs 96");
  std::string cut;
  put<std::uint32_t>(cut, 96);
  expect_refused_read(file("cut.vti", appended("", ext, cut + f32.substr(0, 50))), "");
  expect_refused_read(file("off.vti", vti_head("") + arr + "appended\" offset=\"100000\"/>" + kVtiTail +
                                          "<AppendedData encoding=\"raw\">_" + cut + f32 + "</AppendedData></VTKFile>"),
                      "");
  expect_refused_read(file("noapp.vti", vti_head("") + arr + "appended\" offset=\"0\"/>" + kVtiTail + "</VTKFile>"),
                      "AppendedData");
  // Base64 garbage and truncation.
  expect_refused_read(file("b64.vti", vti_head("") + arr + "binary\">!!!!</DataArray>" + kVtiTail + "</VTKFile>"),
                      "base64");
  expect_refused_read(file("b64cut.vti", vti_head("") + arr + "binary\">" + base64(cut + f32).substr(0, 40) +
                                             "</DataArray>" + kVtiTail + "</VTKFile>"),
                      "");
  // zlib: a block that inflates past its declared size, corrupt data, a
  // compressor keymesh does not know.
  const std::string zroot = " compressor=\"vtkZLibDataCompressor\"";
  {
    const std::string z = zlib_bytes(f32 + f32);  // 192 bytes behind a header saying 96
    std::string block;
    put<std::uint32_t>(block, 1);
    put<std::uint32_t>(block, 96);
    put<std::uint32_t>(block, 96);
    put<std::uint32_t>(block, static_cast<std::uint32_t>(z.size()));
    expect_refused_read(file("zpast.vti", appended(zroot, ext, block + z)), "more than the 96 bytes");
    std::string junk = z;
    for (std::size_t i = 2; i < junk.size(); i += 3) junk[i] = static_cast<char>(junk[i] ^ 0x5a);
    expect_refused_read(file("zjunk.vti", appended(zroot, ext, block + junk)), "zlib");
  }
  expect_refused_read(file("lz4.vti", appended(" compressor=\"vtkLZ4DataCompressor\"", ext, vtk_block(f32, false, false, false))),
                      "vtkLZ4DataCompressor");
  expect_refused_read(file("order.vti", appended(" byte_order=\"Middle\"", ext, vtk_block(f32, false, false, false))),
                      "byte_order");
  expect_refused_read(file("htype.vti", appended(" header_type=\"UInt16\"", ext, vtk_block(f32, false, false, false))),
                      "header_type");
}

TEST_F(VolumeIo, VtiHugeDeclarationsRefusedBeforeAllocation) {
  const std::string huge = "0 " + std::to_string(kHuge - 1) + " 0 " + std::to_string(kHuge - 1) + " 0 ";
  const std::string data = vtk_block(sample_bytes<float>(), false, false, false);
  for (const std::string& ext : {huge + std::to_string(kHuge - 1), huge + "0"}) {
    SCOPED_TRACE(ext);
    const std::string tail = kVtiTail + "<AppendedData encoding=\"raw\">_" + data + "</AppendedData></VTKFile>";
    expect_refused_read(file("huge.vti", vti_head("", ext) +
                                             "<DataArray type=\"Float32\" Name=\"f\" format=\"appended\" offset=\"0\"/>" +
                                             tail));
    expect_refused_read(file("hugeascii.vti", vti_head("", ext) + "<DataArray type=\"Float32\" Name=\"f\" format=\"ascii\">" +
                                                  ascii_samples<float>() + "</DataArray>" + kVtiTail + "</VTKFile>"));
  }
  // A zlib header claiming 2^40-byte blocks from 16 bytes of data.
  std::string block;
  put<std::uint64_t>(block, 1);
  put<std::uint64_t>(block, std::uint64_t{1} << 40);
  put<std::uint64_t>(block, 0);
  put<std::uint64_t>(block, 16);
  expect_refused_read(file("zhuge.vti", vti_head(" header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\"",
                                                  "0 1023 0 1023 0 262143") +
                                            "<DataArray type=\"Float32\" Name=\"f\" format=\"appended\" offset=\"0\"/>" +
                                            kVtiTail + "<AppendedData encoding=\"raw\">_" + block +
                                            std::string(16, 'x') + "</AppendedData></VTKFile>"));
}

// ---- dispatch --------------------------------------------------------------------

TEST_F(VolumeIo, DispatchRefusesUnknownAndMissingFiles) {
  expect_refused_read(file("v.xyz", "data"), "unknown volume format");
  expect_refused_read(path("missing.nrrd"), "");
  expect_refused_read(path("missing.vti"), "");
  expect_refused_read(path("missing.nii"), "");
  expect_refused_read(path("missing.den"), "");
  fs::create_directories(path("dir.nrrd"));
  expect_refused_read(path("dir.nrrd"), "");
}

// A mesh or grid file where a volume is read is refused by its kind, not as
// an unknown format.
TEST_F(VolumeIo, DispatchSaysAMeshOrGridIsNotAVolume) {
  expect_refused_read(file("surface.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\n"),
                      "legacy VTK is an unstructured grid format, not a volume (expected .vti");
  expect_refused_read(file("mesh.ply", "ply\n"), "PLY is a surface mesh format, not a volume");
}

// ---- plane by plane (the streamed and distributed contours' reader) --------------

// Reads every plane of `p` through open_volume_planes, in two slabs (plane
// 0, then the rest), and expects the samples, type, geometry and field name
// read_volume gives, the name being `name`.
void expect_planes_equal_reader(const std::string& p, const RawOptions* raw = nullptr,
                                const std::string& name = "scalars") {
  SCOPED_TRACE(p);
  const ImageGrid whole = read_volume(p, raw);
  auto source = open_volume_planes(p, raw);
  const ImageGrid& head = source->header();
  EXPECT_EQ(whole.name, name);
  EXPECT_EQ(head.name, whole.name);
  EXPECT_EQ(head.dims, whole.dims);
  EXPECT_EQ(head.type, whole.type);
  EXPECT_EQ(head.spacing, whole.spacing);
  EXPECT_EQ(head.origin, whole.origin);
  const std::size_t plane = static_cast<std::size_t>(whole.dims[0] * whole.dims[1]) * scalar_size(whole.type);
  std::vector<std::byte> got(plane * static_cast<std::size_t>(whole.dims[2]));
  source->read_planes(0, 1, got.data());
  source->read_planes(1, whole.dims[2] - 1, got.data() + plane);
  EXPECT_TRUE(std::memcmp(got.data(), whole.bytes.data(), got.size()) == 0);
}

TEST_F(VolumeIo, PlanesOfNiftiEqualTheReader) {
  for_each_nifti_type([&](std::int16_t code, auto tag, ScalarType) {
      using T = decltype(tag);
      for (bool big : {false, true})
        for (float slope : {0.0f, 0.5f}) {  // unscaled, then scaled: float samples
          Nifti n;
          n.datatype = code;
          n.bitpix = static_cast<std::int16_t>(8 * sizeof(T));
          n.slope = slope;
          n.inter = slope == 0 ? 0.0f : -3.0f;
          n.vox_offset = 352 + 32;  // an extension before the data
          expect_planes_equal_reader(file("p.nii", n.header(big) + std::string(36, '\0') + sample_bytes<T>(big)));
        }
  });
}

TEST_F(VolumeIo, PlanesOfNrrdEqualTheReader) {
  for (bool big : {false, true})
    expect_planes_equal_reader(file("p.nrrd", nrrd_header("short", std::string("encoding: raw\nendian: ") +
                                                                     (big ? "big" : "little") + "\nspacings: 0.5 2 3\n") +
                                                  sample_bytes<std::int16_t>(big)));
  file("lines.raw", "first line\nsecond\nXY" + sample_bytes<float>());
  expect_planes_equal_reader(
      file("l.nhdr", nrrd_header("float", "encoding: raw\nline skip: 2\nbyte skip: 2\ndata file: lines.raw\n"
                                          "space dimension: 3\nspace directions: (0,0,2) (0,1.5,0) (3,4,0)\n"
                                          "space origin: (10,-20,30.5)")));
  RawOptions o;
  o.dims = {4, 3, 2};
  o.type = ScalarType::UInt16;
  o.big_endian = true;
  o.header_bytes = 5;
  expect_planes_equal_reader(file("p.raw", "HEAD!" + sample_bytes<std::uint16_t>(true)), &o);
}

// A .vti with raw appended samples streams; its field keeps the array's
// Name on both paths, and a .vti with no Name or an empty one gives
// "scalars" on both (io::volume_field_name), as every other format does.
TEST_F(VolumeIo, PlanesOfAppendedVtiEqualTheReaderNameIncluded) {
  const std::string block = vtk_block(sample_bytes<float>(), false, false, false);
  // (the DataArray's Name attribute, the field name both paths must give)
  const std::pair<std::string, std::string> cases[] = {
      {" Name=\"density &amp; &lt;co&gt;\"", "density & <co>"}, {" Name=\"\"", "scalars"}, {"", "scalars"}};
  for (const auto& [attribute, name] : cases) {
    const std::string array = "    <DataArray type=\"Float32\"" + attribute + " format=\"appended\" offset=\"0\"/>\n";
    const std::string vti = vti_head(" header_type=\"UInt32\"") + array + kVtiTail +
                            "<AppendedData encoding=\"raw\">\n   _" + block + "\n</AppendedData>\n</VTKFile>\n";
    expect_planes_equal_reader(file("named.vti", vti), nullptr, name);
  }
}

TEST_F(VolumeIo, PlanesRefusedByNameWhenNotReadableByOffset) {
  const std::string vti = file("v.vti", "<VTKFile/>");
  expect_refused([&] { open_volume_planes(vti, nullptr); }, vti, "plane by plane");
  const std::string den = file("v.den", "not a den");
  expect_refused([&] { open_volume_planes(den, nullptr); }, den, "plane by plane");
  // The header's checks still apply: a body shorter than declared.
  const std::string short_body = file("s.nrrd", nrrd_header("float", "encoding: raw") + "abc");
  expect_refused([&] { open_volume_planes(short_body, nullptr); }, short_body, "declares");
}

// gzip NRRD and .nii.gz are inflated forward once; reads that go back (a
// kept plane, or a rewind) give the planes read_volume gives.
TEST_F(VolumeIo, GzipPlanesEqualTheWholeVolumeInAnyReadOrder) {
  const std::string gz = file("g.nrrd", nrrd_header("float", "encoding: gzip") + gzip_bytes(sample_bytes<float>()));
  Nifti n;
  n.slope = 2, n.inter = -1;
  const std::string niigz = file("g.nii.gz", gzip_bytes(n.file(false, sample_bytes<float>())));
  for (const std::string& p : {gz, niigz}) {
    const ImageGrid whole = read_volume(p);
    auto source = open_volume_planes(p, nullptr);
    ASSERT_EQ(source->header().dims, whole.dims) << p;
    ASSERT_EQ(source->header().type, whole.type) << p;
    const std::size_t plane = static_cast<std::size_t>(whole.dims[0] * whole.dims[1]) * scalar_size(whole.type);
    const auto* want = static_cast<const std::byte*>(whole.data());
    std::vector<std::byte> got(2 * plane);
    auto expect_planes = [&](Id first, Id count) {
      source->read_planes(first, count, got.data());
      EXPECT_EQ(0, std::memcmp(got.data(), want + first * plane, count * plane)) << p << " planes " << first << "+" << count;
    };
    expect_planes(1, 1);  // skips plane 0
    expect_planes(0, 1);  // behind the stream: rewinds
    expect_planes(0, 2);  // plane 0 kept, plane 1 inflated
    expect_planes(1, 1);  // kept
  }
  // Cut short: the read that meets the end names the file.
  const std::string data = gzip_bytes(sample_bytes<float>());
  const std::string cut = file("cut.nrrd", nrrd_header("float", "encoding: gzip") + data.substr(0, data.size() / 2));
  auto source = open_volume_planes(cut, nullptr);
  std::vector<std::byte> out(static_cast<std::size_t>(kCount) * 4);
  expect_refused([&] { source->read_planes(0, 2, out.data()); }, cut, "gzip data ends");
}

}  // namespace
}  // namespace keymesh::io
