# What the slowest tests cost (seconds on a 2-core machine; ctest's COST
# property). ctest -j starts the most costly tests first, but a fresh build
# tree has no Testing/Temporary/CTestCostData.txt, so CI's clean clone ran
# them in the order they were added: py.python_module and the example tests
# last, one core idle while the last long one ran. With a cost they start
# first; once ctest has run, its own measured costs take over. Refresh from
# build/Testing/Temporary/CTestCostData.txt when the slowest tests change
# (docs/decisions/ci-time.md).
set(KEYMESH_TEST_COSTS
  py.python_module=30 py.test_hardening_mpi=39 py.test_field_names_cli=31 py.test_mpi_cli=31
  py.test_labels_mpi_cli=27 LabelsMultilod.ChunkTaskEqualsOneCall=20 py.test_labels_pieces_mpi_cli=19
  py.test_self_intersections_cli=18 py.test_coarsen_distributed_cli=15 py.test_tet_contour_crosscheck=11
  py.test_history=11 py.test_coarsen_pieces_mpi_cli=9 py.test_flying_edges_crosscheck=9 py.test_hardening=8
  LabelsMultilod.NoiseStress=8 py.test_vti_interop=8)

# keymesh_test_cost(<test name> <variable>): the test's cost, or 0 when not listed.
function(keymesh_test_cost name variable)
  set(cost 0)
  foreach(entry IN LISTS KEYMESH_TEST_COSTS)
    if(entry MATCHES "^(.+)=([0-9.]+)$" AND CMAKE_MATCH_1 STREQUAL name)
      set(cost ${CMAKE_MATCH_2})
    endif()
  endforeach()
  set(${variable} ${cost} PARENT_SCOPE)
endfunction()

# keymesh_test_costs_file(<file>): a ctest include file setting the listed
# costs on tests that exist when it runs (gtest_discover_tests adds its tests
# in an include file too, read before this one; unknown names are ignored).
function(keymesh_test_costs_file file)
  set(text "")
  foreach(entry IN LISTS KEYMESH_TEST_COSTS)
    if(entry MATCHES "^(.+)=([0-9.]+)$")
      string(APPEND text "set_tests_properties([=[${CMAKE_MATCH_1}]=] PROPERTIES COST ${CMAKE_MATCH_2})\n")
    endif()
  endforeach()
  file(WRITE ${file} "${text}")
endfunction()
