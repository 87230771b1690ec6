# Precompiled headers (bench/RESULTS.md "2026-11-30 — Build time: precompiled headers"): parsing
# the standard library, Eigen, JSON and GoogleTest took about 8 s of every 10-17 s test file and
# every library file, and CLI11 about 9 s of each command file. Three headers are precompiled once
# each and reused by every target of their kind, so a build parses them three times instead of
# two hundred:
#   talus_pch_library  the layers (position-independent code, as they are built)
#   talus_pch_tests    the GoogleTest programs (position-independent executables, GCC's default)
#   talus_pch_tool     the command-line tool (with CLI11)
# GCC uses a precompiled header only when the code-generation flags match (-fPIC against -fPIE),
# hence one per kind; it refuses a mismatched one with -Winvalid-pch, which CMake adds and -Werror
# makes fatal, so a mismatch fails the build rather than slowing it silently.
# Only third-party and standard headers are precompiled: each file still includes what it uses,
# and scripts/lint's clang-tidy reads the files without them (scripts/compile_commands_without_pch.py),
# so a missing include fails the lint even though the precompiled header would hide it here.
# Off in the fuzzing build (fuzz/run.sh: clang with sanitizers, a folder of its own).
if(TALUS_FUZZ)
  set(talus_pch_default OFF)
else()
  set(talus_pch_default ON)
endif()
option(TALUS_PCH "Precompile the standard, Eigen, JSON, GoogleTest and CLI11 headers"
       ${talus_pch_default})

# the headers most files include (counted over the sources: the standard ones each in 20-115
# files, Eigen through host/math.hpp in nearly all, JSON in 26)
set(TALUS_PCH_COMMON
  <algorithm> <array> <chrono> <cmath> <cstdint> <cstdio> <cstdlib> <cstring> <filesystem>
  <fstream> <functional> <iostream> <limits> <map> <memory> <optional> <random> <sstream>
  <string> <utility> <vector> <Eigen/Dense> <Eigen/Sparse> <nlohmann/json.hpp>)

# one target that only compiles the precompiled header, with the include folders and flags of the
# targets that reuse it. The flags include the optimisation level: GCC keeps the level a header
# was parsed at for its inline functions, so -O1 test files on an -O3 header compiled Eigen's and
# GoogleTest's code at -O3 (multibody_test: code generation 5.2 -> 9.3 s)
function(talus_pch_target name)
  if(NOT TALUS_PCH)
    return()
  endif()
  cmake_parse_arguments(PCH "PIC" "" "HEADERS;LINK;OPTIONS" ${ARGN})
  set(source ${CMAKE_BINARY_DIR}/generated/${name}.cpp)
  file(CONFIGURE OUTPUT ${source} CONTENT "// the object that carries ${name}'s precompiled header\n")
  add_library(${name} OBJECT ${source})
  target_link_libraries(${name} PRIVATE ${PCH_LINK})
  target_compile_options(${name} PRIVATE ${PCH_OPTIONS})
  set_target_properties(${name} PROPERTIES POSITION_INDEPENDENT_CODE ${PCH_PIC})
  target_precompile_headers(${name} PRIVATE ${TALUS_PCH_COMMON} ${PCH_HEADERS})
endfunction()

# targets reuse their kind's header: talus_use_pch(library|tests|tool TARGET...)
function(talus_use_pch kind)
  if(NOT TALUS_PCH)
    return()
  endif()
  foreach(target ${ARGN})
    target_precompile_headers(${target} REUSE_FROM talus_pch_${kind})
  endforeach()
endfunction()

set(TALUS_PCH_LINK Eigen3::Eigen nlohmann_json::nlohmann_json)
talus_pch_target(talus_pch_library PIC LINK ${TALUS_PCH_LINK})
talus_pch_target(talus_pch_tool LINK ${TALUS_PCH_LINK} CLI11::CLI11 HEADERS <CLI/CLI.hpp>)
# talus_pch_tests is made in tests/CMakeLists.txt, with the test files' own optimisation flags
