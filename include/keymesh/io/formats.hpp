#pragma once
// The one table of the file formats keymesh knows: what a file of each holds
// (a surface mesh, an unstructured grid or a volume), the functions that read
// and write it, and whether a volume can be read plane by plane (streamable:
// what the streamed and distributed contours read). read_mesh / write_mesh,
// read_grid / write_grid, read_volume / write_volume and open_volume_planes
// dispatch through it; the command line and the Python module ask it what a
// file name holds and list its extensions in their help; every
// unknown-format message lists its extensions. A new format is one row of
// src/io/formats.cpp and its own file under src/io.
#include <array>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "keymesh/mesh/image_grid.hpp"
#include "keymesh/mesh/plane_source.hpp"
#include "keymesh/mesh/surface_mesh.hpp"
#include "keymesh/mesh/unstructured_grid.hpp"

namespace keymesh::io {

enum class DataKind { Surface, Grid, Volume };

using SurfaceReader = SurfaceMesh (*)(const std::string& path);
using SurfaceWriter = void (*)(const SurfaceMesh& mesh, const std::string& path);
using GridReader = UnstructuredGrid (*)(const std::string& path);
using GridWriter = void (*)(const UnstructuredGrid& grid, const std::string& path);
using VolumeReader = ImageGrid (*)(const std::string& path);
using VolumeWriter = void (*)(const ImageGrid& grid, const std::string& path);
using PlaneOpener = std::unique_ptr<PlaneSource> (*)(const std::string& path);
// The .pvtp index of a distributed mesh's pieces, written by rank 0 (see
// io/mesh_io.hpp): no single process writes the whole mesh in this format.
using PiecesIndexWriter = void (*)(const std::string& path, const SurfaceMesh& like,
                                   const std::vector<std::string>& pieces, bool global_point_ids);

struct Format {
  std::string_view name{};                     // "PLY", "DICOM" (a folder format: "a DICOM folder")
  std::array<std::string_view, 2> extensions{};  // lower case, with the dot; none for a folder format
  DataKind kind = DataKind::Surface;
  // The function of the format's kind, or monostate when keymesh does not
  // read (write) the format.
  std::variant<std::monostate, SurfaceReader, GridReader, VolumeReader> read{};
  std::variant<std::monostate, SurfaceWriter, GridWriter, VolumeWriter> write{};
  PlaneOpener open_planes = nullptr;  // a volume read plane by plane
  // A folder format (DICOM series, Zarr): does this folder hold one.
  bool (*holds)(const std::string& folder) = nullptr;
  // Raw samples: dims, type, spacing and byte order come from RawOptions
  // (--dims, --type, ...), not from the file; read_volume and
  // open_volume_planes take them, and refuse the file without them.
  bool headerless = false;
  // When a streamable format can really be read plane by plane ("with raw
  // appended data": a .vti's samples must be stored by offset).
  std::string_view streams_if = {};
  PiecesIndexWriter write_pieces_index = nullptr;

  bool readable() const { return read.index() != 0 || headerless; }
  bool writable() const { return write.index() != 0; }
  bool streamable() const { return open_planes != nullptr || headerless; }
  bool is_folder() const { return holds != nullptr; }
};

// The format's reader (writer) of type Fn, e.g. reader_of<SurfaceReader>:
// null when the format holds another kind or keymesh does not read it.
template <class Fn>
Fn reader_of(const Format& format) {
  const Fn* fn = std::get_if<Fn>(&format.read);
  return fn ? *fn : nullptr;
}
template <class Fn>
Fn writer_of(const Format& format) {
  const Fn* fn = std::get_if<Fn>(&format.write);
  return fn ? *fn : nullptr;
}

// Every format, in the order messages and help list them.
std::span<const Format> formats();

// Lower-case extension including the dot (".ply"; ".gz" for a.nii.gz), or
// "" when the file name has none: what unknown-extension messages quote.
std::string file_extension(const std::string& path);

// The format a file name says: the longest extension of the table the name
// ends with, case-insensitively (".nii.gz" before any shorter one); null
// when none does. For outputs, and inputs known not to be folders.
const Format* format_by_name(const std::string& path);
// The format of an input: a folder's (DICOM series, Zarr) when the path is
// a directory, else format_by_name.
const Format* input_format(const std::string& path);

// The extensions of the formats of one kind keymesh reads (or writes), in
// table order, separated by `separator`: for help strings, ".ply .obj .stl
// .vtp .pvtp". Read by name alone: a headerless format (.raw, which needs
// --dims) is not listed as read, and folder formats have no extension
// (folder_formats names them).
std::string extensions_of(DataKind kind, bool written, std::string_view separator = " ");
// "a DICOM or Zarr folder".
std::string folder_formats();

// What unknown-format messages say is accepted, from the table:
// surfaces ".ply, .obj, .stl, .vtp; .pvtp to read; .glb to write", grids
// ".vtu or .vtk", volumes read ".vti, .nrrd, ..., a DICOM or Zarr folder, or
// .raw with --dims", volumes written ".vti, .nrrd or .raw", volumes read
// plane by plane ".vti with raw appended data, ..., a DICOM or Zarr folder".
std::string accepted_surfaces();
std::string accepted_grids();
std::string accepted_volumes(bool written);
std::string accepted_plane_sources();

}  // namespace keymesh::io
