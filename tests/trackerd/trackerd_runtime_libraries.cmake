# cmake -DEXECUTABLE=... -DMAX_LIBRARIES=N -DFORBIDDEN="regex|..." -P trackerd_runtime_libraries.cmake
# Fails when the executable's shared-library closure (DT_NEEDED, transitively, as the dynamic
# loader resolves it) holds more than MAX_LIBRARIES libraries or one matching a FORBIDDEN regex.
# Every mapped library costs start-up time and, with lock_memory, resident memory; CHOLMOD and GDAL
# are the back end's and OpenCV imgcodecs' ways in, which the tracker does not need.
cmake_minimum_required(VERSION 3.25)
string(REPLACE "|" ";" FORBIDDEN "${FORBIDDEN}")
file(GET_RUNTIME_DEPENDENCIES
  EXECUTABLES "${EXECUTABLE}"
  RESOLVED_DEPENDENCIES_VAR resolved
  UNRESOLVED_DEPENDENCIES_VAR unresolved)
if(unresolved)
  message(FATAL_ERROR "${EXECUTABLE}: unresolved shared libraries: ${unresolved}")
endif()
list(LENGTH resolved count)
set(bad "")
foreach(library IN LISTS resolved)
  get_filename_component(name "${library}" NAME)
  foreach(pattern IN LISTS FORBIDDEN)
    if(name MATCHES "${pattern}")
      list(APPEND bad "${name}")
    endif()
  endforeach()
endforeach()
list(JOIN resolved "\n  " listing)
message(STATUS "${EXECUTABLE}: ${count} shared libraries:\n  ${listing}")
if(bad)
  list(JOIN bad ", " bad)
  message(FATAL_ERROR "${EXECUTABLE} needs ${bad}")
endif()
if(count GREATER MAX_LIBRARIES)
  message(FATAL_ERROR "${EXECUTABLE} needs ${count} shared libraries, more than ${MAX_LIBRARIES}")
endif()
