# The layers of keymesh, bottom to top, and the layers each one may use.
#
# One table for two things: CMakeLists.txt builds one target per library
# layer linking exactly the layers listed here, and cmake/check_layers.cmake
# (run by every build and by ctest) refuses any #include "keymesh/<layer>/..."
# of a layer that is not listed. A layer may only use layers above it in this
# list (checked by keymesh_check_layer_table). A layer's files are
# include/keymesh/<layer>/ and src/<layer>/ (private headers included); the
# python layer is python/src/. docs/ARCHITECTURE.md ("Layers") says what each
# layer holds.
set(KEYMESH_LAYERS core parallel device weld keyreduce mesh analyze io generate distributed cuda backend cli python)

set(KEYMESH_LAYER_USES_core        "")
set(KEYMESH_LAYER_USES_parallel    core)
set(KEYMESH_LAYER_USES_device      core parallel)
set(KEYMESH_LAYER_USES_weld        core parallel)
set(KEYMESH_LAYER_USES_keyreduce   core parallel weld)
set(KEYMESH_LAYER_USES_mesh        core parallel weld keyreduce)
set(KEYMESH_LAYER_USES_analyze     core parallel weld keyreduce mesh)
set(KEYMESH_LAYER_USES_io          core parallel weld keyreduce mesh)
set(KEYMESH_LAYER_USES_generate    core parallel device weld keyreduce mesh analyze)
set(KEYMESH_LAYER_USES_distributed core parallel device weld keyreduce mesh analyze io generate)
set(KEYMESH_LAYER_USES_cuda        core parallel device weld keyreduce mesh generate)
set(KEYMESH_LAYER_USES_backend     core parallel device weld keyreduce mesh generate cuda)
set(KEYMESH_LAYER_USES_cli         core parallel device weld keyreduce mesh analyze io generate distributed cuda backend)
set(KEYMESH_LAYER_USES_python      core parallel device weld keyreduce mesh analyze io generate distributed cuda backend)

# The layers built into the library (cli is the `keymesh` executable, python
# the module; both link every library layer through keymesh_lib).
set(KEYMESH_LIBRARY_LAYERS core parallel device weld keyreduce mesh analyze io generate distributed cuda backend)

# Fails (FATAL_ERROR) when the table names an unknown layer or lets a layer
# use itself or a layer above it: the order above is what "downward" means.
function(keymesh_check_layer_table)
  set(below "")
  foreach(layer IN LISTS KEYMESH_LAYERS)
    if(NOT DEFINED KEYMESH_LAYER_USES_${layer})
      message(FATAL_ERROR "cmake/layers.cmake: layer '${layer}' has no KEYMESH_LAYER_USES_${layer}")
    endif()
    foreach(used IN LISTS KEYMESH_LAYER_USES_${layer})
      if(NOT used IN_LIST below)
        message(FATAL_ERROR "cmake/layers.cmake: layer '${layer}' uses '${used}', which is not a layer below it")
      endif()
    endforeach()
    list(APPEND below ${layer})
  endforeach()
endfunction()
