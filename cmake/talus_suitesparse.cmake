# CHOLMOD and SuiteSparse_config, the vehicle's direct solver (vehicle/direct_solver.cpp), as the
# imported targets SuiteSparse::CHOLMOD and SuiteSparse::SuiteSparseConfig. Debian 12's SuiteSparse
# (5.12) ships neither a CMake config nor a pkg-config file, so they are found by their header and
# libraries; SuiteSparse 7 ships a config with these target names, which would replace this file.
# Included by the build (CMakeLists.txt) and by the installed talusConfig.cmake, so a consumer of
# the installed package finds them the same way. Sets TALUS_SUITESPARSE_FOUND; fails nothing itself.
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
find_library(CHOLMOD_LIBRARY cholmod)
find_library(SUITESPARSE_CONFIG_LIBRARY suitesparseconfig)
if(CHOLMOD_INCLUDE_DIR AND CHOLMOD_LIBRARY AND SUITESPARSE_CONFIG_LIBRARY)
  set(TALUS_SUITESPARSE_FOUND TRUE)
  # a project that found SuiteSparse 7's own config already has them
  if(NOT TARGET SuiteSparse::SuiteSparseConfig)
    add_library(SuiteSparse::SuiteSparseConfig UNKNOWN IMPORTED)
    set_target_properties(SuiteSparse::SuiteSparseConfig PROPERTIES
      IMPORTED_LOCATION "${SUITESPARSE_CONFIG_LIBRARY}"
      INTERFACE_INCLUDE_DIRECTORIES "${CHOLMOD_INCLUDE_DIR}")
  endif()
  if(NOT TARGET SuiteSparse::CHOLMOD)
    add_library(SuiteSparse::CHOLMOD UNKNOWN IMPORTED)
    set_target_properties(SuiteSparse::CHOLMOD PROPERTIES
      IMPORTED_LOCATION "${CHOLMOD_LIBRARY}"
      INTERFACE_INCLUDE_DIRECTORIES "${CHOLMOD_INCLUDE_DIR}"
      INTERFACE_LINK_LIBRARIES SuiteSparse::SuiteSparseConfig)
  endif()
else()
  set(TALUS_SUITESPARSE_FOUND FALSE)
endif()
