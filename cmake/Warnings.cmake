# Compiler warnings and sanitizers for every target of the project.
# vp_target_defaults(<target>) is called by each add_library/add_executable of ours.

add_library(vp_compile_options INTERFACE)
target_compile_options(vp_compile_options INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wcast-align
  -Wunused -Woverloaded-virtual -Wnull-dereference -Wdouble-promotion
  -Wformat=2 -Wimplicit-fallthrough)
if(VP_WERROR)
  target_compile_options(vp_compile_options INTERFACE -Werror)
endif()
if(VP_SANITIZE)
  target_compile_options(vp_compile_options INTERFACE
    -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  target_link_options(vp_compile_options INTERFACE -fsanitize=address,undefined)
endif()
if(VP_FUZZ)
  # Every library gets libFuzzer's coverage instrumentation (without its main) and the address
  # and undefined-behaviour sanitizers; the harnesses of tests/fuzz link -fsanitize=fuzzer.
  # -O1: fast enough to fuzz, still exact stack traces.
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "VP_FUZZ needs clang (libFuzzer), got ${CMAKE_CXX_COMPILER_ID}: "
                        "use the preset 'fuzz'")
  endif()
  target_compile_options(vp_compile_options INTERFACE
    -O1 -fsanitize=fuzzer-no-link,address,undefined -fno-omit-frame-pointer
    -fno-sanitize-recover=undefined)
  target_link_options(vp_compile_options INTERFACE -fsanitize=address,undefined)
endif()

function(vp_target_defaults target)
  target_link_libraries(${target} PRIVATE vp_compile_options)
endfunction()
