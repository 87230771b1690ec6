# What `cmake --install` puts where (docs/embedding.md), included by CMakeLists.txt after the
# targets are defined. Every path is relative to the prefix, so an install can be moved.
include(CMakePackageConfigHelpers)

# the tool, and the layers' archives exported as talus::host ... talus::io with the facade as
# talus::talus (the tool itself is not a target a consumer links)
set(TALUS_INSTALLED_LAYERS host vehicle solvers terrain digging sim2real io)
set(TALUS_CMAKE_INSTALL_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/talus)
set(TALUS_DATA_INSTALL_DIR ${CMAKE_INSTALL_DATADIR}/talus/data)
install(TARGETS talus RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
foreach(layer ${TALUS_INSTALLED_LAYERS})
  list(APPEND TALUS_INSTALLED_TARGETS talus_${layer})
endforeach()
install(TARGETS ${TALUS_INSTALLED_TARGETS} talus_embed EXPORT talusTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(EXPORT talusTargets NAMESPACE talus:: DESTINATION ${TALUS_CMAKE_INSTALL_DIR})

# the headers keep their folders under include/talus/ (their includes are folder-relative), with
# the kernels' shared layouts the solvers' headers include; the facade is talus/talus.hpp, whose
# own include of host/error.hpp resolves beside it
foreach(folder kernels ${TALUS_INSTALLED_LAYERS})
  install(DIRECTORY ${CMAKE_SOURCE_DIR}/${folder}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/talus/${folder}
          FILES_MATCHING PATTERN "*.hpp" PATTERN "*.h")
endforeach()
install(FILES ${CMAKE_SOURCE_DIR}/embed/talus.hpp DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/talus)

# data/ where host/data_files looks beside an installed program (bin/../share/talus/data), and
# where the package tells the facade to look (TALUS_INSTALL_DATA_DIR, embed/talus.hpp)
install(DIRECTORY ${CMAKE_SOURCE_DIR}/data/ DESTINATION ${TALUS_DATA_INSTALL_DIR})

# the CMake package: talusConfig.cmake finds the dependencies, then loads the exported targets;
# the version file accepts requests for the same major.minor (0.x: the API may still change)
configure_package_config_file(${CMAKE_SOURCE_DIR}/cmake/talusConfig.cmake.in
                              ${CMAKE_BINARY_DIR}/generated/talusConfig.cmake
                              INSTALL_DESTINATION ${TALUS_CMAKE_INSTALL_DIR}
                              PATH_VARS TALUS_DATA_INSTALL_DIR)
write_basic_package_version_file(${CMAKE_BINARY_DIR}/generated/talusConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/generated/talusConfig.cmake
              ${CMAKE_BINARY_DIR}/generated/talusConfigVersion.cmake
              ${CMAKE_SOURCE_DIR}/cmake/talus_suitesparse.cmake
        DESTINATION ${TALUS_CMAKE_INSTALL_DIR})

# the pkg-config file, for the facade and the layers under it (no PLplot, NLopt, PNG: sim2real
# and io are not in it). The archives' own dependencies are named by the files CMake found; the
# prefix is the .pc file's folder's, so the install can move
function(talus_pc_library path out)
  get_filename_component(name ${path} NAME_WE)
  string(REGEX REPLACE "^lib" "" name ${name})
  get_filename_component(dir ${path} DIRECTORY)
  if(NOT dir IN_LIST CMAKE_CXX_IMPLICIT_LINK_DIRECTORIES)
    set(flags "-L${dir} ")
  endif()
  set(${out} "${flags}-l${name}" PARENT_SCOPE)
endfunction()
get_target_property(TALUS_EMBREE_LIBRARY embree LOCATION)
set(TALUS_PC_LIBS "")
foreach(library ${TALUS_EMBREE_LIBRARY} ${CHOLMOD_LIBRARY} ${SUITESPARSE_CONFIG_LIBRARY})
  talus_pc_library(${library} flag)
  string(APPEND TALUS_PC_LIBS " ${flag}")
endforeach()
foreach(library ${CMAKE_DL_LIBS})
  string(APPEND TALUS_PC_LIBS " -l${library}")
endforeach()
# threads: glibc 2.34 and later need no flag (CMAKE_THREAD_LIBS_INIT is empty there)
string(APPEND TALUS_PC_LIBS " ${CMAKE_THREAD_LIBS_INIT}")
string(STRIP "${TALUS_PC_LIBS}" TALUS_PC_LIBS)
file(RELATIVE_PATH TALUS_PC_PREFIX /prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig /prefix)
string(REGEX REPLACE "/$" "" TALUS_PC_PREFIX "${TALUS_PC_PREFIX}")
configure_file(${CMAKE_SOURCE_DIR}/cmake/talus.pc.in ${CMAKE_BINARY_DIR}/generated/talus.pc @ONLY)
install(FILES ${CMAKE_BINARY_DIR}/generated/talus.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
