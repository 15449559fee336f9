#!/bin/sh
# One build step, timed (cmake/TranslucencyBuildTiming.cmake puts it in front
# of every compile, link and custom command):
#   time_build_step.sh LOG KIND TARGET OUTPUT -- COMMAND...
# appends "user_s sys_s wall_s KIND TARGET OUTPUT" to LOG (GNU time: the CPU
# of COMMAND and every child it waited for) and exits with COMMAND's status.
log=$1 kind=$2 target=$3 output=$4
shift 4
[ "$1" = "--" ] && shift
exec /usr/bin/time -a -o "$log" -f "%U %S %e $kind $target $output" "$@"
