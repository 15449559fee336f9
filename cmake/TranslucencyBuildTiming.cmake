# Where a build's CPU goes (Documentation/Building.md). Not part of a normal
# build: scripts/profile_build.sh passes this file as CMAKE_PROJECT_INCLUDE,
# which wraps every compile, link and custom command (the VTK wrappers, Qt's
# moc, the plugin's XML and help generators) in scripts/time_build_step.sh.
# Each step appends "user sys wall kind target output" (CPU seconds of the
# step and its children) to TRANSLUCENCY_BUILD_TIMING_LOG.
if (NOT TRANSLUCENCY_BUILD_TIMING_LOG)
  message(FATAL_ERROR "TranslucencyBuildTiming.cmake: set TRANSLUCENCY_BUILD_TIMING_LOG to a file")
endif ()
set(_translucency_timer "${CMAKE_CURRENT_LIST_DIR}/../scripts/time_build_step.sh")
get_filename_component(_translucency_timer "${_translucency_timer}" ABSOLUTE)
set(_translucency_log "${TRANSLUCENCY_BUILD_TIMING_LOG}")
set_property(GLOBAL PROPERTY RULE_LAUNCH_COMPILE
  "${_translucency_timer} ${_translucency_log} compile <TARGET_NAME> <SOURCE> --")
set_property(GLOBAL PROPERTY RULE_LAUNCH_LINK
  "${_translucency_timer} ${_translucency_log} link <TARGET_NAME> <TARGET> --")
set_property(GLOBAL PROPERTY RULE_LAUNCH_CUSTOM
  "${_translucency_timer} ${_translucency_log} custom <TARGET_NAME> <OUTPUT> --")
message(STATUS "Build timing: every step is logged to ${_translucency_log}")
