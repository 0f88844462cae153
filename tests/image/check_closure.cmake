# Fails when PROGRAM loads OpenCV's imgcodecs or GDAL (libcvo/image codes the daemons' images):
#   cmake -DPROGRAM=path -P check_closure.cmake
execute_process(COMMAND ldd "${PROGRAM}" OUTPUT_VARIABLE closure RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "ldd ${PROGRAM} failed (${status}): is it built?")
endif()
string(REGEX MATCHALL "[^\n]*(imgcodecs|gdal)[^\n]*" found "${closure}")
if(found)
  string(REPLACE ";" "\n" found "${found}")
  message(FATAL_ERROR "${PROGRAM} loads OpenCV's imgcodecs or GDAL:\n${found}")
endif()
string(REGEX MATCHALL "\n" lines "${closure}")
list(LENGTH lines count)
message(STATUS "${PROGRAM}: ${count} shared libraries, neither imgcodecs nor GDAL")
