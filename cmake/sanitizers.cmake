# SPDX-License-Identifier: Apache-2.0
# UBERSIM_SANITIZE and UBERSIM_FUZZ (docs/reliability.md), included by the top-level
# CMakeLists.txt before any target is made, so every target gets the flags: kernel, plugins,
# tools and tests alike, and a bad access is caught wherever it happens.
include_guard(GLOBAL)

if(UBERSIM_SANITIZE)
  # Assertions stay on: RapidJSON's and Eigen's checks catch misuse no sanitizer sees, and
  # libstdc++'s catch an index past a vector's end that still lies inside its capacity.
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer
                      -fno-sanitize-recover=undefined -UNDEBUG -D_GLIBCXX_ASSERTIONS)
  add_link_options(-fsanitize=address,undefined)
  if(CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    # Bugs of other projects the checks must pass over, each with its reason in the file.
    add_compile_options(-fsanitize-ignorelist=${CMAKE_CURRENT_LIST_DIR}/sanitizer_ignorelist.txt)
  endif()
  # The runtimes' defaults, built into every executable (sanitizer_options.cpp), so a report
  # looks the same under ctest, the Python tests and a shell.
  add_library(ubersim_sanitizer_options OBJECT ${CMAKE_CURRENT_LIST_DIR}/sanitizer_options.cpp)
  link_libraries("$<$<STREQUAL:$<TARGET_PROPERTY:TYPE>,EXECUTABLE>:ubersim_sanitizer_options>")
endif()

# libFuzzer: every library gets coverage instrumentation; tests/fuzz links the fuzzer itself.
# Outside the fuzz targets the sanitizer runtime supplies the coverage hooks, hence the need for
# UBERSIM_SANITIZE.
if(UBERSIM_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "UBERSIM_FUZZ needs clang (libFuzzer): -DCMAKE_CXX_COMPILER=clang++")
  endif()
  if(NOT UBERSIM_SANITIZE)
    message(FATAL_ERROR "UBERSIM_FUZZ needs UBERSIM_SANITIZE=ON")
  endif()
  add_compile_options(-fsanitize=fuzzer-no-link)
endif()
