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
#include <type_traits>
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
  // A surface writer that splits polygons into triangles (STL, glTF): not
  // an output for polygons (the dual's).
  bool triangles_only = false;

  bool readable() const { return read.index() != 0 || headerless; }
  bool writable() const { return write.index() != 0; }
  bool streamable() const { return open_planes != nullptr || headerless; }
  bool is_folder() const { return holds != nullptr; }
};

namespace detail {
template <class Fn, class Variant>
struct IsAlternative;
template <class Fn, class... Ts>
struct IsAlternative<Fn, std::variant<Ts...>> : std::bool_constant<(std::is_same_v<Fn, Ts> || ...)> {};
}  // namespace detail

// The format's function of type Fn (a reader type or a writer type, e.g.
// function_of<SurfaceReader>): null when the format holds another kind or
// keymesh does not read (write) it.
template <class Fn>
Fn function_of(const Format& format) {
  const Fn* fn = nullptr;
  if constexpr (detail::IsAlternative<Fn, decltype(format.read)>::value) fn = std::get_if<Fn>(&format.read);
  else fn = std::get_if<Fn>(&format.write);
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

// Throws the InputError saying that `path` names no format of `kind` keymesh
// reads (writes), listing the extensions the table accepts:
// "<path>: unknown mesh file extension '.x' (accepted: ...)",
// "<path>: unknown unstructured grid format '.x' (use ...)",
// "<path>: unknown volume format (expected ...)",
// "<path>: cannot write this volume format (expected ...)".
[[noreturn]] void refuse_format(const std::string& path, DataKind kind, bool written);

// The function of type Fn (a reader or writer type) the table gives a file
// name (format_by_name); refuse_format when it has none.
template <class Fn>
Fn function_for(const std::string& path) {
  const Format* format = format_by_name(path);
  if (const Fn fn = format ? function_of<Fn>(*format) : nullptr) return fn;
  constexpr bool written = !detail::IsAlternative<Fn, decltype(Format::read)>::value;
  constexpr DataKind kind = std::is_same_v<Fn, SurfaceReader> || std::is_same_v<Fn, SurfaceWriter> ? DataKind::Surface
                            : std::is_same_v<Fn, GridReader> || std::is_same_v<Fn, GridWriter>     ? DataKind::Grid
                                                                                                  : DataKind::Volume;
  refuse_format(path, kind, written);
}

// The extensions of the formats of one kind keymesh reads (or writes), in
// table order, separated by `separator`: for help strings, ".ply .obj .stl
// .vtp .pvtp". Read by name alone: a headerless format (.raw, which needs
// --dims) is not listed as read, and folder formats have no extension
// (folder_formats names them).
std::string extensions_of(DataKind kind, bool written, std::string_view separator = " ");
// "a DICOM or Zarr folder".
std::string folder_formats();
// The surface formats written with their polygons kept (.ply .obj .vtp),
// or with polygons split into triangles (triangles_only: .stl .glb).
std::string polygon_extensions(bool kept, std::string_view separator = " ");
// The formats an index of distributed pieces is written in (".pvtp").
std::string pieces_index_extensions(std::string_view separator = " ");

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
