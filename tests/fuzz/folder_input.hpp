#pragma once
// The folder readers (a DICOM series, a Zarr array) take a folder, not one
// file: their fuzz input is a folder packed into one byte string, a record
// per file,
//
//   KMFILE:<name>\n<the file's bytes>\nKMFILE:<name>\n<bytes> ...
//
// (bytes before the first record are ignored; a file's bytes end where the
// next "\nKMFILE:" starts). Names are relative paths of letters, digits and
// "._-" joined by '/' ("0/.zarray", "IM0001"), at most 4 parts; any other
// name (absolute, "..", an empty part, too long) is dropped, so that no
// input writes outside its folder. The record named "@open" is no file: its
// bytes name the sub-folder to give the reader (an OME-Zarr level read by
// its own folder). tests/fuzz/make_corpus.py packs its seed folders so
// (pack_folder). The folder is made afresh for every input, one per process
// under $TMPDIR (or /tmp).
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <string_view>

#include "keymesh/core/error.hpp"

namespace keymesh::fuzz {

inline constexpr std::string_view kFileRecord = "KMFILE:";
inline constexpr std::string_view kOpenRecord = "@open";
// Enough for a series or a chunked array; an input cannot fill the disk.
inline constexpr int kMaxFolderFiles = 64;
inline constexpr std::size_t kMaxNameBytes = 64;
inline constexpr int kMaxNameParts = 4;

// True when `name` is a relative path made only of safe parts.
inline bool safe_relative_name(std::string_view name) {
  if (name.empty() || name.size() > kMaxNameBytes) return false;
  int parts = 0;
  std::size_t start = 0;
  for (std::size_t i = 0; i <= name.size(); ++i) {
    if (i < name.size() && name[i] != '/') {
      const char c = name[i];
      if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' ||
            c == '-'))
        return false;
      continue;
    }
    const std::string_view part = name.substr(start, i - start);
    if (part.empty() || part == "." || part == ".." || ++parts > kMaxNameParts) return false;
    start = i + 1;
  }
  return true;
}

// Unpacks `data` into a fresh folder "<tmp>/keymesh-fuzz-<pid>-folder/<leaf>"
// and returns the path to give the reader (that folder, or its "@open"
// sub-folder). The leaf is part of the input a reader sees ("in.zarr" is a
// Zarr folder by name).
inline std::string temp_folder(std::string_view data, const std::string& leaf) {
  namespace fs = std::filesystem;
  const char* tmp = std::getenv("TMPDIR");
  const fs::path root = fs::path(tmp && *tmp ? tmp : "/tmp") / ("keymesh-fuzz-" + std::to_string(::getpid()) + "-folder");
  const fs::path folder = root / leaf;
  std::error_code ec;
  fs::remove_all(root, ec);
  fs::create_directories(folder, ec);
  if (ec) throw InputError(folder.string() + ": cannot make the fuzz folder");
  const std::string separator = std::string("\n").append(kFileRecord);
  fs::path open = folder;
  int files = 0;
  for (std::size_t at = data.find(kFileRecord); at != std::string_view::npos && files < kMaxFolderFiles;) {
    const std::size_t name_at = at + kFileRecord.size();
    const std::size_t name_end = data.find('\n', name_at);
    if (name_end == std::string_view::npos) break;
    const std::size_t next = data.find(separator, name_end);
    const std::string_view name = data.substr(name_at, name_end - name_at);
    const std::string_view bytes =
        data.substr(name_end + 1, (next == std::string_view::npos ? data.size() : next) - name_end - 1);
    at = next == std::string_view::npos ? next : next + 1;
    if (name == kOpenRecord) {
      if (safe_relative_name(bytes)) open = folder / std::string(bytes);
      continue;
    }
    if (!safe_relative_name(name)) continue;
    const fs::path file = folder / std::string(name);
    fs::create_directories(file.parent_path(), ec);
    if (ec || fs::is_directory(file, ec)) continue;  // a part of the path is a file, or the name a folder
    std::FILE* f = std::fopen(file.c_str(), "wb");
    if (!f) continue;
    const bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
    if (std::fclose(f) != 0 || !ok) throw InputError(file.string() + ": cannot write the fuzz input");
    ++files;
  }
  return open.string();
}

}  // namespace keymesh::fuzz
