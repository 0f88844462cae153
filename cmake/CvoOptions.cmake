# Compiler settings shared by every target of the project: warnings, sanitizers, ccache.

find_program(CVO_CCACHE ccache)
if(CVO_CCACHE AND NOT CMAKE_CXX_COMPILER_LAUNCHER)
  set(CMAKE_C_COMPILER_LAUNCHER "${CVO_CCACHE}")
  set(CMAKE_CXX_COMPILER_LAUNCHER "${CVO_CCACHE}")
endif()

add_library(cvo_warnings INTERFACE)
target_compile_options(cvo_warnings INTERFACE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
                                              -Wcast-align -Wunused -Woverloaded-virtual)
if(CVO_WERROR)
  target_compile_options(cvo_warnings INTERFACE -Werror)
endif()

if(CVO_SANITIZE STREQUAL "address")
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
elseif(CVO_SANITIZE STREQUAL "thread")
  add_compile_options(-fsanitize=thread -fno-omit-frame-pointer)
  add_link_options(-fsanitize=thread)
elseif(NOT CVO_SANITIZE STREQUAL "")
  message(FATAL_ERROR "CVO_SANITIZE must be '', 'address' or 'thread', not '${CVO_SANITIZE}'")
endif()

# Where the read-only shared data lives next to a checkout; tests skip when it is absent.
set(CVO_SHARED_DATA_DIR "${PROJECT_SOURCE_DIR}/../shared/data" CACHE PATH "Shared real data (optional)")
