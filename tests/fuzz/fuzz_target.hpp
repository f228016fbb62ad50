#pragma once
// One fuzz target per reader: a file `<name>_fuzz.cpp` holding
//
//   KEYMESH_FUZZ_TARGET(name) { ...hand `data` to the reader... }
//
// Built two ways from the same source:
// - with KEYMESH_LIBFUZZER (clang, `make fuzz`): the body becomes
//   LLVMFuzzerTestOneInput of its own executable fuzz_<name>;
// - otherwise (the ordinary build, `make test`): fuzz_replay_test.cpp
//   includes every target, which registers itself by name, and replays
//   tests/fuzz/corpus/<name>/ and tests/fuzz/regressions/<name>/ through it.
//
// The readers' documented failures (InputError, LimitError) are expected
// outcomes of hostile bytes; anything else escaping (std::bad_alloc,
// std::length_error, a crash, a sanitizer report) is a bug.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <string_view>

#include "keymesh/core/error.hpp"

namespace keymesh::fuzz {

using Body = void (*)(std::string_view data);

// Runs body on the bytes; swallows the errors a reader may legitimately throw.
inline int run_guarded(Body body, const std::uint8_t* data, std::size_t size) {
  try {
    body(std::string_view(reinterpret_cast<const char*>(data), size));
  } catch (const InputError&) {
  } catch (const LimitError&) {
  }
  return 0;
}

// Readers that only take a path get the bytes through a per-process file
// (suffix chooses the format); rewritten for every input.
inline std::string temp_file(std::string_view bytes, const std::string& suffix) {
  const char* dir = std::getenv("TMPDIR");
  const std::string path = std::string(dir && *dir ? dir : "/tmp") + "/keymesh-fuzz-" + std::to_string(::getpid()) +
                           suffix;
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw InputError(path + ": cannot write the fuzz input");
  const bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  if (std::fclose(f) != 0 || !ok) throw InputError(path + ": cannot write the fuzz input");
  return path;
}

inline std::map<std::string, Body>& registry() {
  static std::map<std::string, Body> targets;
  return targets;
}

inline bool register_target(const char* name, Body body) {
  registry()[name] = body;
  return true;
}

}  // namespace keymesh::fuzz

#ifdef KEYMESH_LIBFUZZER
#define KEYMESH_FUZZ_TARGET(name)                                                              \
  static void keymesh_fuzz_##name(std::string_view data);                                      \
  extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {          \
    return keymesh::fuzz::run_guarded(keymesh_fuzz_##name, data, size);                        \
  }                                                                                            \
  static void keymesh_fuzz_##name(std::string_view data)
#else
#define KEYMESH_FUZZ_TARGET(name)                                                              \
  static void keymesh_fuzz_##name(std::string_view data);                                      \
  [[maybe_unused]] static const bool keymesh_fuzz_registered_##name =                          \
      keymesh::fuzz::register_target(#name, keymesh_fuzz_##name);                             \
  static void keymesh_fuzz_##name(std::string_view data)
#endif
