#pragma once
// A shared module of keymesh's own build (a MODULE library such as
// libkeymesh_gdcm.so) opened on first use rather than linked: what it pulls
// in (a library's static initialiser, its dependencies' relocations) costs
// only the runs that need it. The build puts each module beside every
// binary that may open it (the `keymesh` command, the test programs, the
// fuzzers in the build directory; the Python extension in its package
// folder, setup.py's install too), and it is looked for beside the binary
// object holding this code: the executable, or the extension's .so.
#include <string>

namespace keymesh::io {

// The address of `entry` (a C symbol) in the module file `file_name`,
// opened once per process (RTLD_LOCAL; never closed). Throws InputError
// naming the path looked at when the module is missing or unloadable, or
// lacks `entry`; `purpose` says what needed it ("reading a DICOM series").
void* loadable_module_entry(const std::string& file_name, const char* entry, const std::string& purpose);

}  // namespace keymesh::io
