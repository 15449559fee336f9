# Unity builds (Documentation/Building.md, issue 33): each listed target's C++
# sources are compiled in a few combined units instead of one unit per file,
# so the headers they share (Eigen, VTK, CLI11, nlohmann json, the STL) are
# parsed, and their inline functions and templates compiled, once per unit.
# CMake writes the units (unity_<n>_cxx.cxx in the target's CMakeFiles/): a
# changed source rebuilds its unit, so an incremental build stays correct.
# A source with its own compile definitions (Apps/Provenance.cxx) is compiled
# on its own by CMake. Off: -DTRANSLUCENCY_UNITY_BUILD=OFF (one unit per file,
# as before; a unity build hides a missing include that the other files of
# the unit happen to provide, so CI should build once with it off).
option(TRANSLUCENCY_UNITY_BUILD "Compile each library's sources in a few combined units" ON)

# translucency_unity_build(<target> [UNITS <n>] [SEPARATE <source>...])
#  UNITS     how many combined units (default 2, one per core of a 2-core
#            machine: fewer would leave a core idle while the target builds)
#  SEPARATE  sources (relative to the target's source directory) compiled on
#            their own: the heaviest ones, where combining saves nothing and
#            costs the balance between the units.
function(translucency_unity_build target)
  if (NOT TRANSLUCENCY_UNITY_BUILD)
    return ()
  endif ()
  cmake_parse_arguments(arg "" "UNITS" "SEPARATE" ${ARGN})
  if (NOT arg_UNITS)
    set(arg_UNITS 2)
  endif ()
  get_target_property(aliased ${target} ALIASED_TARGET)
  if (aliased)
    set(target ${aliased})
  endif ()
  get_target_property(dir ${target} SOURCE_DIR)
  set(separate)
  foreach (source IN LISTS arg_SEPARATE)
    get_filename_component(source "${source}" ABSOLUTE BASE_DIR "${dir}")
    list(APPEND separate "${source}")
  endforeach ()
  get_target_property(sources ${target} SOURCES)
  set(combined 0)
  foreach (source IN LISTS sources)
    if (NOT source MATCHES "\\.(cxx|cpp)$")
      continue ()
    endif ()
    get_filename_component(source "${source}" ABSOLUTE BASE_DIR "${dir}")
    if (NOT source IN_LIST separate)
      math(EXPR combined "${combined} + 1")
    endif ()
  endforeach ()
  math(EXPR batch "(${combined} + ${arg_UNITS} - 1) / ${arg_UNITS}")
  if (batch LESS 2)
    return ()
  endif ()
  set_target_properties(${target} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE ${batch})
  # GCC warns about a class using a type of an anonymous namespace when the
  # class is defined in an included file, which a unity unit's sources are
  # (it is silent for the main file): the same code compiled alone is fine.
  # A pragma in the units only, so that the flags of the target's other
  # sources (and their ccache entries) stay those of a build without units.
  set_target_properties(${target} PROPERTIES UNITY_BUILD_CODE_BEFORE_INCLUDE
    "#if defined(__GNUC__) && !defined(__clang__)\n#pragma GCC diagnostic ignored \"-Wsubobject-linkage\"\n#endif")
  if (separate)
    set_source_files_properties(${separate} TARGET_DIRECTORY ${target}
      PROPERTIES SKIP_UNITY_BUILD_INCLUSION ON)
  endif ()
endfunction()
