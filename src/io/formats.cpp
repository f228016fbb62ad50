#include "keymesh/io/formats.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include "keymesh/core/error.hpp"
#include "keymesh/io/mesh_io.hpp"
#include "keymesh/io/plane_source.hpp"
#include "dicom.hpp"
#include "mesh_formats.hpp"
#include "volume_formats.hpp"
#include "zarr.hpp"

namespace keymesh::io {

namespace {

using K = DataKind;

// A folder that is not a Zarr array or image is read as a DICOM series (whose
// reader names what it finds when it is not one).
bool holds_dicom_series(const std::string& folder) { return !is_zarr_folder(folder); }

ImageGrid read_dicom_series(const std::string& folder) { return read_all_planes(*open_dicom_series(folder)); }
ImageGrid read_zarr(const std::string& folder) { return read_all_planes(*open_zarr(folder)); }

// The order is the order of every list in messages and help. constexpr: the
// commands' help strings read it during static initialisation.
constexpr Format kFormats[] = {
    {"PLY", {".ply"}, K::Surface, SurfaceReader{read_ply}, SurfaceWriter{write_ply}},
    {"OBJ", {".obj"}, K::Surface, SurfaceReader{read_obj}, SurfaceWriter{write_obj}},
    {.name = "STL", .extensions = {".stl"}, .kind = K::Surface, .read = SurfaceReader{read_stl},
     .write = SurfaceWriter{write_stl}, .triangles_only = true},
    {"VTK XML PolyData", {".vtp"}, K::Surface, SurfaceReader{read_vtp}, SurfaceWriter{write_vtp}},
    {.name = "ParaView parallel PolyData", .extensions = {".pvtp"}, .kind = K::Surface,
     .read = SurfaceReader{read_pvtp}, .write_pieces_index = write_pvtp},
    {.name = "glTF binary", .extensions = {".glb"}, .kind = K::Surface, .write = SurfaceWriter{write_gltf_binary},
     .triangles_only = true},
    {"VTK XML UnstructuredGrid", {".vtu"}, K::Grid, GridReader{read_vtu}, GridWriter{write_vtu}},
    {"legacy VTK", {".vtk"}, K::Grid, GridReader{read_legacy_vtk}, GridWriter{write_legacy_vtk}},
    {.name = "VTK XML ImageData", .extensions = {".vti"}, .kind = K::Volume, .read = VolumeReader{read_vti},
     .write = VolumeWriter{write_vti}, .open_planes = open_vti_planes, .streams_if = "with raw appended data"},
    {"NRRD", {".nrrd"}, K::Volume, VolumeReader{read_nrrd}, VolumeWriter{write_nrrd}, open_nrrd_planes},
    {"detached NRRD header", {".nhdr"}, K::Volume, VolumeReader{read_nrrd}, {}, open_nrrd_planes},
    {"NIfTI-1", {".nii", ".nii.gz"}, K::Volume, VolumeReader{read_nifti}, {}, open_nifti_planes},
    {"VolPack density", {".den"}, K::Volume, VolumeReader{read_den}, {}},
    {.name = "raw samples", .extensions = {".raw"}, .kind = K::Volume, .write = VolumeWriter{write_raw},
     .headerless = true},
    {.name = "DICOM", .kind = K::Volume, .read = VolumeReader{read_dicom_series}, .open_planes = open_dicom_series,
     .holds = holds_dicom_series},
    {.name = "Zarr", .kind = K::Volume, .read = VolumeReader{read_zarr}, .open_planes = open_zarr,
     .holds = is_zarr_folder},
};

// What a headerless format needs to be read, in messages.
constexpr std::string_view kHeaderlessNeeds = " with --dims";

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

bool has(const Format& f, DataKind kind, bool written) {
  return f.kind == kind && (written ? f.writable() : f.readable());
}

// "a, b or c"
std::string or_list(const std::vector<std::string>& items) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (i > 0) out.append(i + 1 == items.size() ? " or " : ", ");
    out.append(items[i]);
  }
  return out;
}

std::string joined(const std::vector<std::string>& items, std::string_view separator) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (i > 0) out.append(separator);
    out.append(items[i]);
  }
  return out;
}

// The extensions of the formats `keep` accepts, in table order.
template <class Keep>
std::vector<std::string> extensions_where(Keep keep) {
  std::vector<std::string> out;
  for (const Format& f : kFormats)
    if (keep(f))
      for (std::string_view e : f.extensions)
        if (!e.empty()) out.emplace_back(e);
  return out;
}

}  // namespace

std::span<const Format> formats() { return kFormats; }

std::string file_extension(const std::string& path) {
  const std::size_t slash = path.find_last_of("/\\");
  const std::size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  return lower(path.substr(dot));
}

const Format* format_by_name(const std::string& path) {
  const std::string name = lower(path);
  const Format* best = nullptr;
  std::size_t best_size = 0;
  for (const Format& f : kFormats)
    for (std::string_view e : f.extensions)
      if (!e.empty() && e.size() > best_size && name.size() >= e.size() &&
          name.compare(name.size() - e.size(), e.size(), e) == 0)
        best = &f, best_size = e.size();
  return best;
}

const Format* input_format(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_directory(path, ec)) return format_by_name(path);
  for (const Format& f : kFormats)
    if (f.is_folder() && f.holds(path)) return &f;
  return nullptr;
}

std::string extensions_of(DataKind kind, bool written, std::string_view separator) {
  return joined(extensions_where([&](const Format& f) { return has(f, kind, written) && (written || !f.headerless); }),
                separator);
}

std::string folder_formats() {
  std::vector<std::string> names;
  for (const Format& f : kFormats)
    if (f.is_folder()) names.emplace_back(f.name);
  return std::string("a ").append(or_list(names)).append(" folder");
}

std::string polygon_extensions(bool kept, std::string_view separator) {
  return joined(extensions_where([&](const Format& f) { return has(f, K::Surface, true) && f.triangles_only != kept; }),
                separator);
}

std::string pieces_index_extensions(std::string_view separator) {
  return joined(extensions_where([](const Format& f) { return f.write_pieces_index != nullptr; }), separator);
}

std::string accepted_surfaces() {
  auto list = [](bool read, bool write) {
    return joined(extensions_where([&](const Format& f) {
                    return f.kind == DataKind::Surface && f.readable() == read && f.writable() == write;
                  }),
                  ", ");
  };
  std::string out = list(true, true);
  if (const std::string r = list(true, false); !r.empty()) out += "; " + r + " to read";
  if (const std::string w = list(false, true); !w.empty()) out += "; " + w + " to write";
  return out;
}

std::string accepted_grids() {
  return or_list(extensions_where([](const Format& f) { return has(f, K::Grid, false); }));
}

std::string accepted_volumes(bool written) {
  if (written) return or_list(extensions_where([](const Format& f) { return has(f, K::Volume, true); }));
  // Formats read by name first, then folders, then those that need options.
  std::string out = extensions_of(K::Volume, false, ", ") + ", " + folder_formats();
  const auto headerless = [](const Format& f) { return has(f, K::Volume, false) && f.headerless; };
  for (const std::string& e : extensions_where(headerless)) out.append(", or ").append(e).append(kHeaderlessNeeds);
  return out;
}

void refuse_format(const std::string& path, DataKind kind, bool written) {
  // An input that is not there at all: that is the cause, whatever its name says.
  struct stat st {};
  if (!written && ::stat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) throw InputError(path + ": no such file");
    throw InputError(path + ": cannot open: " + std::strerror(errno));
  }
  switch (kind) {
    case K::Surface:
      throw InputError(path + ": unknown mesh file extension '" + file_extension(path) + "' (accepted: " +
                       accepted_surfaces() + ")");
    case K::Grid:
      throw InputError(path + ": unknown unstructured grid format '" + file_extension(path) + "' (use " +
                       accepted_grids() + ")");
    case K::Volume: break;
  }
  if (written) throw InputError(path + ": cannot write this volume format (expected " + accepted_volumes(true) + ")");
  throw InputError(path + ": unknown volume format (expected " + accepted_volumes(false) + ")");
}

std::string accepted_plane_sources() {
  std::vector<std::string> items;
  for (const Format& f : kFormats) {
    if (!f.streamable() || f.is_folder()) continue;
    std::vector<std::string> exts;
    for (std::string_view e : f.extensions)
      if (!e.empty()) exts.emplace_back(e);
    std::string item = joined(exts, "/");
    if (f.headerless) item += kHeaderlessNeeds;
    else if (!f.streams_if.empty()) item.append(" ").append(f.streams_if);
    items.push_back(item);
  }
  items.push_back(folder_formats());
  return joined(items, ", ");
}

}  // namespace keymesh::io
