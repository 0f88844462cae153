# cmake -DTARGET=... -DLIBRARIES="a|b|..." -DFORBIDDEN="cvo_slam|..." -P trackerd_link_interface.cmake
# Fails when the target's transitive link libraries (LIBRARIES, gathered at configure time by
# tests/daemon/CMakeLists.txt) hold a FORBIDDEN target: the tracker must not link the back end.
cmake_minimum_required(VERSION 3.25)
string(REPLACE "|" ";" LIBRARIES "${LIBRARIES}")
string(REPLACE "|" ";" FORBIDDEN "${FORBIDDEN}")
set(bad "")
foreach(library IN LISTS FORBIDDEN)
  if(library IN_LIST LIBRARIES)
    list(APPEND bad "${library}")
  endif()
endforeach()
if(bad)
  list(JOIN bad ", " bad)
  message(FATAL_ERROR "${TARGET} links ${bad} (its link libraries: ${LIBRARIES})")
endif()
message(STATUS "${TARGET} links: ${LIBRARIES}")
