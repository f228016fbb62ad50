#pragma once
// A shared module of keymesh's own build (a MODULE library such as
// libkeymesh_gdcm.so) opened on first use rather than linked: what it pulls
// in (a library's static initialiser, its dependencies' relocations) costs
// only the runs that need it. The build puts each module beside every
// binary that may open it (the `keymesh` command, the test programs, the
// fuzzers in the build directory; the Python extension in its package
// folder, setup.py's install too), and it is looked for beside the binary
// object holding this code: the executable, or the extension's .so.
#include <cstdint>
#include <string>

#include "keymesh/core/error.hpp"

namespace keymesh {

// How the module's symbols (and its libraries') are seen by code loaded
// after it: Local keeps them to the module; Global is for a library that
// dlopens plugins expecting its symbols in the global scope (Open MPI's
// components).
enum class ModuleScope { Local, Global };

// The address of `entry` (a C symbol) in the module file `file_name`,
// opened once per process (never closed). Throws InputError naming the
// path looked at when the module is missing or unloadable, or lacks
// `entry`; `purpose` says what needed it ("reading a DICOM series").
void* loadable_module_entry(const std::string& file_name, const char* entry, const std::string& purpose,
                            ModuleScope scope = ModuleScope::Local);

// The table of functions a module's `entry` returns (a C function taking
// nothing), refused by name unless its first field, `version`, is the
// `version` this build knows.
template <class Table>
const Table& loadable_module_table(const std::string& file_name, const char* entry, std::uint32_t version,
                                   const std::string& purpose, ModuleScope scope = ModuleScope::Local) {
  const auto table_of = reinterpret_cast<const Table* (*)()>(loadable_module_entry(file_name, entry, purpose, scope));
  const Table* table = table_of();
  if (!table || table->version != version)
    throw InputError(purpose + ": keymesh's module " + file_name + " is of another keymesh build (reinstall keymesh)");
  return *table;
}

}  // namespace keymesh
