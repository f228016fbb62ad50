// The format table (io/formats.hpp): its rows are consistent, a file name
// finds the one format whose extension ends it, every dispatcher refuses an
// unknown name with a message listing the table's extensions, and those
// messages are the ones docs/ERRORS.md documents.
#include "keymesh/io/formats.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "keymesh/core/error.hpp"
#include "keymesh/io/grid_io.hpp"
#include "keymesh/io/mesh_io.hpp"
#include "keymesh/io/plane_source.hpp"
#include "keymesh/io/volume_io.hpp"

using namespace keymesh;
using namespace keymesh::io;

namespace {

// The message `call` throws as InputError ("" when it does not).
template <class Call>
std::string message_of(Call call) {
  try {
    call();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::string errors_doc() {
  std::ifstream in(std::string(KEYMESH_SOURCE_DIR) + "/docs/ERRORS.md");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// An empty file of that name in a folder of this test's own: a missing file
// is refused as missing, whatever its name (below).
std::string existing_file(const std::string& name) {
  const std::filesystem::path folder =
      std::filesystem::temp_directory_path() / ("keymesh-formats-test-" + std::to_string(::getpid()));
  std::filesystem::create_directories(folder);
  const std::string path = (folder / name).string();
  std::ofstream(path).put('x');
  return path;
}

// The variant alternative a reader or writer of `kind` must be (0: none).
std::size_t alternative_of(DataKind kind) {
  return kind == DataKind::Surface ? 1 : kind == DataKind::Grid ? 2 : 3;
}

}  // namespace

TEST(FormatTable, RowsAreConsistent) {
  std::set<std::string> seen;
  for (const Format& f : formats()) {
    SCOPED_TRACE(std::string(f.name));
    EXPECT_TRUE(f.readable() || f.writable());
    // A reader or writer is of the format's kind.
    if (f.read.index() != 0) { EXPECT_EQ(f.read.index(), alternative_of(f.kind)); }
    if (f.write.index() != 0) { EXPECT_EQ(f.write.index(), alternative_of(f.kind)); }
    // Only volumes are read plane by plane; folders have no extension and are read as planes.
    if (f.streamable()) { EXPECT_EQ(f.kind, DataKind::Volume); }
    EXPECT_EQ(f.is_folder(), f.extensions[0].empty());
    if (f.is_folder()) { EXPECT_TRUE(f.open_planes); }
    for (std::string_view e : f.extensions) {
      if (e.empty()) continue;
      EXPECT_EQ(e[0], '.');
      for (char c : e) EXPECT_FALSE(c >= 'A' && c <= 'Z') << e;
      EXPECT_TRUE(seen.insert(std::string(e)).second) << e << " names two formats";
    }
  }
}

TEST(FormatTable, NameFindsTheFormatWhoseExtensionEndsIt) {
  for (const Format& f : formats())
    for (std::string_view e : f.extensions) {
      if (e.empty()) continue;
      std::string upper = "dir.vti/Name" + std::string(e);
      for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
      EXPECT_EQ(format_by_name("dir.vti/name" + std::string(e)), &f) << e;
      EXPECT_EQ(format_by_name(upper), &f) << upper;
    }
  // The longest extension wins; a name ending in none finds nothing.
  EXPECT_EQ(format_by_name("a.nii.gz"), format_by_name("a.nii"));
  EXPECT_EQ(format_by_name("a.gz"), nullptr);
  EXPECT_EQ(format_by_name("a.ply.bak"), nullptr);
  EXPECT_EQ(format_by_name("noextension"), nullptr);
  EXPECT_EQ(file_extension("dir.d/a.NII.GZ"), ".gz");
  EXPECT_EQ(file_extension("dir.d/name"), "");
}

TEST(FormatTable, UnknownNamesAreRefusedListingTheTablesExtensions) {
  SurfaceMesh mesh;
  UnstructuredGrid grid;
  ImageGrid volume;
  const std::string x = existing_file("x.xyz");
  const std::string mesh_read = message_of([&] { read_mesh(x); });
  const std::string mesh_write = message_of([&] { write_mesh(mesh, x); });
  const std::string grid_read = message_of([&] { read_grid(x); });
  const std::string grid_write = message_of([&] { write_grid(grid, x); });
  const std::string volume_read = message_of([&] { read_volume(x); });
  const std::string volume_write = message_of([&] { write_volume(volume, x); });
  const std::string planes = message_of([&] { open_volume_planes(x, nullptr); });
  for (const std::string* m : {&mesh_read, &mesh_write, &grid_read, &grid_write, &volume_read, &volume_write, &planes})
    EXPECT_EQ(m->rfind(x + ": ", 0), 0u) << *m;
  for (const Format& f : formats()) {
    for (std::string_view e : f.extensions) {
      if (e.empty()) continue;
      const std::string ext(e);
      if (f.kind == DataKind::Surface) {
        EXPECT_NE(mesh_read.find(ext), std::string::npos) << ext;
        EXPECT_NE(mesh_write.find(ext), std::string::npos) << ext;
      }
      if (f.kind == DataKind::Grid && f.readable()) { EXPECT_NE(grid_read.find(ext), std::string::npos) << ext; }
      if (f.kind == DataKind::Grid && f.writable()) { EXPECT_NE(grid_write.find(ext), std::string::npos) << ext; }
      if (f.kind == DataKind::Volume && f.readable()) { EXPECT_NE(volume_read.find(ext), std::string::npos) << ext; }
      if (f.kind == DataKind::Volume && f.writable()) { EXPECT_NE(volume_write.find(ext), std::string::npos) << ext; }
      if (f.streamable()) { EXPECT_NE(planes.find(ext), std::string::npos) << ext; }
    }
    if (f.is_folder()) {
      EXPECT_NE(volume_read.find(f.name), std::string::npos) << f.name;
      EXPECT_NE(planes.find(f.name), std::string::npos) << f.name;
    }
  }
  // A format keymesh only reads is refused for writing, and the other way round.
  EXPECT_NE(message_of([&] { write_mesh(mesh, "x.pvtp"); }).find("unknown mesh file extension '.pvtp'"), std::string::npos);
  EXPECT_NE(message_of([] { read_mesh(existing_file("x.glb")); }).find("unknown mesh file extension '.glb'"),
            std::string::npos);
  // A missing input: that is the cause, whatever its name says.
  for (const char* missing : {"missing.xyz", "missing.glb"}) {
    const std::string m = message_of([&] { read_mesh(missing); });
    EXPECT_EQ(m, std::string(missing) + ": no such file");
  }
  EXPECT_EQ(message_of([] { read_volume("missing.xyz"); }), "missing.xyz: no such file");
  EXPECT_NE(message_of([&] { write_volume(volume, "x.nii.gz"); }).find("cannot write this volume format"),
            std::string::npos);
  EXPECT_NE(message_of([] { read_volume("x.raw"); }).find("needs --dims"), std::string::npos);
  EXPECT_NE(message_of([] { open_volume_planes("x.den", nullptr); }).find("plane by plane"), std::string::npos);
}

// The messages built from the table are the ones users are told about.
TEST(FormatTable, MessagesAreTheDocumentedOnes) {
  const std::string doc = errors_doc();
  ASSERT_FALSE(doc.empty());
  for (const std::string& documented :
       {"unknown mesh file extension '.x' (accepted: " + accepted_surfaces() + ")",
        "unknown volume format (expected " + accepted_volumes(false) + ")",
        "cannot write this volume format (expected " + accepted_volumes(true) + ")",
        "cannot be read plane by plane (" + accepted_plane_sources() + " can;"})
    EXPECT_NE(doc.find(documented), std::string::npos) << documented;
  EXPECT_EQ(accepted_grids(), ".vtu or .vtk");  // the two grid formats keymesh reads and writes
}

// triangles_only says what the writer does: a quad written in a format the
// table marks so comes back as two triangles, in the others as one quad
// (checked on every surface format keymesh both writes and reads back).
TEST(FormatTable, TrianglesOnlyIsWhatTheWriterDoes) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("keymesh_formats_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  SurfaceMesh quad;
  quad.points = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  quad.connectivity = {0, 1, 2, 3};
  quad.offsets = {0, 4};
  int checked = 0;
  for (const Format& f : formats()) {
    if (f.kind != DataKind::Surface || !f.writable() || !f.readable()) continue;
    const std::string path = (dir / ("quad" + std::string(f.extensions[0]))).string();
    write_mesh(quad, path);
    const SurfaceMesh back = read_mesh(path);
    EXPECT_EQ(back.num_cells(), f.triangles_only ? 2 : 1) << f.name;
    ++checked;
  }
  EXPECT_GE(checked, 4);  // PLY, OBJ, STL, VTP
  EXPECT_NE(polygon_extensions(false).find(".stl"), std::string::npos);
  EXPECT_EQ(polygon_extensions(true).find(".stl"), std::string::npos);
  fs::remove_all(dir);
}
