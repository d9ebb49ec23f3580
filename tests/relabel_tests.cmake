# Labels the tests of one gtest executable one by one, after gtest_discover_tests added them.
# ctest includes it (through the file phantasm_add_test writes, see tests/CMakeLists.txt) right
# after the executable's discovered tests, with:
#   phantasm_relabel_target  the executable; ${phantasm_relabel_target}_TESTS lists its tests
#   phantasm_relabel_default the label of the tests not named below
#   phantasm_relabel_fast, _slow, _heavy  names Suite.Test to label fast, slow or heavy (a
#     parameterized test's name covers all its instances, Prefix/Suite.Test/parameter)
#   phantasm_relabel_shared_runs names Suite.Test that read the shared coarse runs: they get one
#     resource lock, so that ctest runs them one at a time (tests/CMakeLists.txt, SHARED_RUNS)
#   phantasm_relabel_cmake   the cmake program
# ctest appends labels rather than replacing them, so each test gets its label here only.
# Each test also gets a cost by its label (heavy 100, slow 10, fast 1): a parallel ctest starts
# the costliest first, so that a run of minutes does not start last and run alone at the end
# (ctest replaces these by measured times once it has them, which a fresh clone has not).
# A listed name that matches no test becomes a failing test, so that renaming or removing a
# test cannot leave its label behind unnoticed.

if(DEFINED ${phantasm_relabel_target}_TESTS) # else the executable is not built yet
  set(phantasm_relabel_unmatched ${phantasm_relabel_fast} ${phantasm_relabel_slow} ${phantasm_relabel_heavy}
                                 ${phantasm_relabel_shared_runs})
  foreach(phantasm_relabel_test IN LISTS ${phantasm_relabel_target}_TESTS)
    string(REGEX REPLACE "^([^/]*/)?([^./]+[.][^./]+)(/.*)?$" "\\2" phantasm_relabel_name
                         "${phantasm_relabel_test}")
    set(phantasm_relabel_label ${phantasm_relabel_default})
    foreach(phantasm_relabel_kind fast slow heavy)
      list(FIND phantasm_relabel_${phantasm_relabel_kind} "${phantasm_relabel_name}" phantasm_relabel_at)
      if(NOT phantasm_relabel_at EQUAL -1)
        set(phantasm_relabel_label ${phantasm_relabel_kind})
        list(REMOVE_ITEM phantasm_relabel_unmatched "${phantasm_relabel_name}")
      endif()
    endforeach()
    set(phantasm_relabel_cost 1)
    if(phantasm_relabel_label STREQUAL "heavy")
      set(phantasm_relabel_cost 100)
    elseif(phantasm_relabel_label STREQUAL "slow")
      set(phantasm_relabel_cost 10)
    endif()
    set_tests_properties("${phantasm_relabel_test}" PROPERTIES LABELS ${phantasm_relabel_label}
                         COST ${phantasm_relabel_cost})
    list(FIND phantasm_relabel_shared_runs "${phantasm_relabel_name}" phantasm_relabel_at)
    if(NOT phantasm_relabel_at EQUAL -1)
      set_tests_properties("${phantasm_relabel_test}" PROPERTIES RESOURCE_LOCK phantasm_shared_coarse_runs)
      list(REMOVE_ITEM phantasm_relabel_unmatched "${phantasm_relabel_name}")
    endif()
  endforeach()
  if(phantasm_relabel_unmatched)
    add_test("${phantasm_relabel_target}.LabelledTestsExist" "${phantasm_relabel_cmake}" -E echo
             "tests/CMakeLists.txt labels tests ${phantasm_relabel_target} does not have: ${phantasm_relabel_unmatched}")
    set_tests_properties("${phantasm_relabel_target}.LabelledTestsExist" PROPERTIES WILL_FAIL TRUE LABELS fast)
  endif()
endif()
