# Test tiers: every ctest test carries at least one of these LABELS.
#
#   unit         a GoogleTest of the core or of the filters' C++ side, a build check
#   integration  a VTK pipeline, the command line, pvpython, an example script
#   mpi          runs several MPI ranks (mpiexec)
#   gui          renders into an X server (xvfb-run: pictures, the ParaView GUI)
#   slow         left out of `make test` (ctest -LE slow); `make test-all` and
#                .ci/run run it. Chosen by measured time (see the comment at
#                each one), never to hide a failure.
#
# How a new test chooses its tiers, where it is registered:
#   add_test(NAME Python.TestX ...)
#   translucency_test_tiers(Python.TestX TIERS integration)
#   translucency_test_tiers(ParaView.TestY3 TIERS integration mpi slow)
# A GoogleTest program: translucency_gtest_tiers(<target> TIERS unit SLOW <Suite.Test>...)
# right after its gtest_discover_tests() (translucency_add_layer_test does it).
# A test of Testing/CMakeLists.txt left without a tier gets one by the default
# rule at the end of that file (mpi if it holds the "mpi" RESOURCE_LOCK, gui if
# it holds "xvfb", else integration) and a configure warning; the test
# Testing.TierLabels fails if any test of the tree (the GoogleTests included)
# has no tier or a SLOW name is not a test.
include_guard(GLOBAL)

set(TRANSLUCENCY_TEST_TIERS unit integration mpi gui slow)

# translucency_test_tiers(<test>... TIERS <tier>...): appends the tiers to
# the tests' LABELS.
function(translucency_test_tiers)
  cmake_parse_arguments(arg "" "" "TIERS" ${ARGN})
  if (NOT arg_TIERS OR NOT arg_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "translucency_test_tiers(<test>... TIERS <tier>...): got '${ARGN}'")
  endif ()
  foreach (tier IN LISTS arg_TIERS)
    if (NOT tier IN_LIST TRANSLUCENCY_TEST_TIERS)
      message(FATAL_ERROR "translucency_test_tiers: '${tier}' is not a tier "
        "(${TRANSLUCENCY_TEST_TIERS})")
    endif ()
  endforeach ()
  set_property(TEST ${arg_UNPARSED_ARGUMENTS} APPEND PROPERTY LABELS ${arg_TIERS})
endfunction()

# translucency_gtest_tiers(<target> TIERS <tier>... [SLOW <Suite.Test>...]):
# the tests gtest_discover_tests(<target>) finds get TIERS, those named in
# SLOW also "slow". The discovered tests exist only when ctest reads the
# tree, so this writes a file ctest includes after the discovery's own.
function(translucency_gtest_tiers target)
  cmake_parse_arguments(arg "" "" "TIERS;SLOW" ${ARGN})
  foreach (tier IN LISTS arg_TIERS)
    if (NOT tier IN_LIST TRANSLUCENCY_TEST_TIERS OR tier STREQUAL "slow")
      message(FATAL_ERROR "translucency_gtest_tiers(${target}): '${tier}' is not a tier "
        "(or is slow: name the slow tests in SLOW)")
    endif ()
  endforeach ()
  list(JOIN arg_TIERS ";" tiers)
  set(file "${CMAKE_CURRENT_BINARY_DIR}/${target}_tiers.cmake")
  set(text "# Written by translucency_gtest_tiers (Testing/TestTiers.cmake).\n")
  string(APPEND text "foreach (name IN ITEMS ${arg_SLOW})\n"
    "  list(FIND ${target}_TESTS \"\${name}\" index)\n"
    "  if (index LESS 0)\n"
    "    message(WARNING \"translucency_gtest_tiers: SLOW test \${name} is not a test of ${target}\")\n"
    "  else ()\n"
    "    set_tests_properties(\"\${name}\" PROPERTIES LABELS \"${tiers};slow\")\n"
    "  endif ()\n"
    "endforeach ()\n")
  file(WRITE "${file}" "${text}")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES "${file}")
endfunction()

# translucency_default_test_tiers(): every test of this directory without a
# tier gets one by the rule above, with a warning naming it.
function(translucency_default_test_tiers)
  get_property(tests DIRECTORY PROPERTY TESTS)
  foreach (test IN LISTS tests)
    get_test_property(${test} LABELS labels)
    set(has_tier OFF)
    foreach (label IN LISTS labels)
      if (label IN_LIST TRANSLUCENCY_TEST_TIERS)
        set(has_tier ON)
      endif ()
    endforeach ()
    if (has_tier)
      continue()
    endif ()
    get_test_property(${test} RESOURCE_LOCK locks)
    if ("mpi" IN_LIST locks)
      set(tiers integration mpi)
    elseif ("xvfb" IN_LIST locks)
      set(tiers integration gui)
    else ()
      set(tiers integration)
    endif ()
    message(AUTHOR_WARNING "${test} has no tier label: labelled '${tiers}' "
      "(choose with translucency_test_tiers, Testing/TestTiers.cmake)")
    translucency_test_tiers(${test} TIERS ${tiers})
  endforeach ()
endfunction()
