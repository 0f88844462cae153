# cmake -DSPY=bin/cvo-spy -P check_spy_starts.cmake
# lcm-spy, started by cvo-spy without a display, must load every class it uses (its plots need
# jchart2d) and find the cvo_lcm types; it then stops at the first window (HeadlessException).
execute_process(COMMAND ${CMAKE_COMMAND} -E env JAVA_TOOL_OPTIONS=-Djava.awt.headless=true
                        ${SPY} --lcm-url memq://
                OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
set(all "${out}${err}")
if(all MATCHES "NoClassDefFoundError|ClassNotFoundException")
  message(FATAL_ERROR "cvo-spy could not load a class lcm-spy needs:\n${all}")
endif()
if(NOT all MATCHES "Found ([0-9]+) LCM types")
  message(FATAL_ERROR "lcm-spy did not report the LCM types it found:\n${all}")
endif()
set(types ${CMAKE_MATCH_1})
if(types LESS 7)
  message(FATAL_ERROR "lcm-spy found only ${types} LCM types, not the cvo_lcm ones:\n${all}")
endif()
if(NOT all MATCHES "HeadlessException")
  message(FATAL_ERROR "lcm-spy did not get as far as its window:\n${all}")
endif()
message(STATUS "lcm-spy loads its classes and ${types} LCM types")
