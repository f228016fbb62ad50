#pragma once
// Small file helpers of the Neuroglancer writer's gtests: a fresh directory,
// a file's bytes, and a directory's output files (chunks/ left out) for
// byte-for-byte comparisons.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

namespace keymesh::tests::neuroglancer_files {

namespace fs = std::filesystem;

inline fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("keymesh_ng_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

inline std::string bytes_of(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Relative path -> bytes of every regular file under dir, chunks/ excepted.
inline std::map<std::string, std::string> output_files(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    const std::string rel = fs::relative(entry.path(), dir).string();
    if (entry.is_regular_file() && rel.rfind("chunks", 0) != 0) files[rel] = bytes_of(entry.path());
  }
  return files;
}

// Names of differing or missing files (empty: the two outputs are equal).
inline std::string output_difference(const fs::path& a, const fs::path& b) {
  const auto fa = output_files(a), fb = output_files(b);
  std::string diff;
  for (const auto& [name, bytes] : fa)
    if (!fb.count(name) || fb.at(name) != bytes) diff += name + " ";
  for (const auto& [name, bytes] : fb)
    if (!fa.count(name)) diff += name + "(only in second) ";
  return diff;
}

}  // namespace keymesh::tests::neuroglancer_files
