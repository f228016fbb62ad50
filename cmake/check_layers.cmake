# The layering check: fails when a file of one layer includes a layer that
# cmake/layers.cmake does not let it use (a lower layer including a higher
# one, or a sibling). Run by every build (target keymesh_layers, which the
# library targets wait for) and by ctest (layers.check); its own test feeds
# it fake trees (tests/layers/check_layers_test.cmake).
#
#   cmake -DKEYMESH_TREE=<source root> [-DKEYMESH_STAMP=<file>] -P cmake/check_layers.cmake
#
# A file's layer is its directory: include/keymesh/<layer>/..., src/<layer>/...
# (private headers too), python/src/... (python). What it includes is read
# from its #include "keymesh/<layer>/..." lines; "../" includes are refused
# since they would hide a layer. On success KEYMESH_STAMP is written.
cmake_minimum_required(VERSION 3.25)
include(${CMAKE_CURRENT_LIST_DIR}/layers.cmake)
keymesh_check_layer_table()
if(NOT KEYMESH_TREE)
  message(FATAL_ERROR "check_layers.cmake: pass -DKEYMESH_TREE=<source root>")
endif()

set(source_globs)
foreach(ext h hpp cpp cu cuh inl ipp)
  list(APPEND source_globs ${KEYMESH_TREE}/include/keymesh/*.${ext} ${KEYMESH_TREE}/src/*.${ext}
       ${KEYMESH_TREE}/python/src/*.${ext})
endforeach()
file(GLOB_RECURSE files RELATIVE ${KEYMESH_TREE} ${source_globs})
list(SORT files)

set(violations)
set(checked 0)
foreach(file IN LISTS files)
  if(file MATCHES "^include/keymesh/([^/]+)/")
    set(layer ${CMAKE_MATCH_1})
  elseif(file MATCHES "^src/([^/]+)/")
    set(layer ${CMAKE_MATCH_1})
  elseif(file MATCHES "^python/src/")
    set(layer python)
  else()
    list(APPEND violations "${file}: not inside a layer's directory (include/keymesh/<layer>/, src/<layer>/)")
    continue()
  endif()
  if(NOT layer IN_LIST KEYMESH_LAYERS)
    list(APPEND violations "${file}: '${layer}' is not a layer of cmake/layers.cmake (add it to the table)")
    continue()
  endif()
  math(EXPR checked "${checked} + 1")
  set(allowed ${KEYMESH_LAYER_USES_${layer}})
  if(allowed)
    string(REPLACE ";" " " allowed_text "${allowed}")
  else()
    set(allowed_text "no other layer")
  endif()
  file(STRINGS ${KEYMESH_TREE}/${file} includes REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]")
  foreach(line IN LISTS includes)
    if(NOT line MATCHES "#[ \t]*include[ \t]*[<\"]([^>\"]+)[>\"]")
      continue()
    endif()
    set(path ${CMAKE_MATCH_1})
    if(path MATCHES "(^|/)\\.\\./")
      list(APPEND violations "${file}: #include \"${path}\": a \"../\" include hides its layer (use keymesh/<layer>/...)")
    elseif(path MATCHES "^keymesh/([^/]+)/")
      set(used ${CMAKE_MATCH_1})
      if(NOT used STREQUAL layer AND NOT used IN_LIST allowed)
        list(APPEND violations
             "${file}: #include \"${path}\": layer ${layer} may not use ${used} (it may use: ${allowed_text})")
      endif()
    elseif(path MATCHES "^keymesh/")
      list(APPEND violations "${file}: #include \"${path}\" names no layer")
    endif()
  endforeach()
endforeach()

if(violations)
  list(LENGTH violations count)
  foreach(v IN LISTS violations)
    message(NOTICE "keymesh layers: ${v}")
  endforeach()
  message(FATAL_ERROR "keymesh layers: ${count} file(s) or include(s) break the layering of cmake/layers.cmake")
endif()
if(KEYMESH_STAMP)
  file(WRITE ${KEYMESH_STAMP} "${checked} files checked\n")
endif()
