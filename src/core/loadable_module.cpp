#include "keymesh/core/loadable_module.hpp"

#include <dlfcn.h>
#include <link.h>
#include <unistd.h>

#include <climits>
#include <filesystem>
#include <system_error>

#include "keymesh/core/error.hpp"

namespace keymesh {

namespace {

// The file of the binary object (executable or shared object) this code
// was linked into.
std::filesystem::path binary_holding_this_code() {
  Dl_info info{};
  link_map* map = nullptr;
  if (dladdr1(reinterpret_cast<void*>(&binary_holding_this_code), &info, reinterpret_cast<void**>(&map),
              RTLD_DL_LINKMAP) != 0 &&
      map && map->l_name && map->l_name[0] != '\0')
    return map->l_name;
  // The main program has no name in its link map: the kernel knows its file.
  char exe[PATH_MAX];
  const ssize_t n = ::readlink("/proc/self/exe", exe, sizeof exe - 1);
  return n > 0 ? std::filesystem::path(std::string(exe, static_cast<std::size_t>(n))) : std::filesystem::path();
}

}  // namespace

void* loadable_module_entry(const std::string& file_name, const char* entry, const std::string& purpose,
                            ModuleScope scope) {
  std::error_code ec;
  std::filesystem::path binary = binary_holding_this_code();
  const std::filesystem::path resolved = std::filesystem::weakly_canonical(binary, ec);
  if (!ec) binary = resolved;
  const std::string path = (binary.parent_path() / file_name).string();
  void* module = ::dlopen(path.c_str(), RTLD_NOW | (scope == ModuleScope::Global ? RTLD_GLOBAL : RTLD_LOCAL));
  if (!module) {
    const char* why = ::dlerror();
    const std::string state =
        std::filesystem::exists(path, ec)
            ? std::string("cannot be loaded: ") + (why ? why : "dlopen failed")
            : "is missing (it is built and installed beside " + binary.filename().string() + ")";
    throw InputError(purpose + " needs keymesh's module " + path + ", which " + state);
  }
  ::dlerror();
  void* found = ::dlsym(module, entry);
  if (!found)
    throw InputError(purpose + ": keymesh's module " + path + " has no " + entry + " (a module of another build?)");
  return found;
}

}  // namespace keymesh
