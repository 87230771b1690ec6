# The installed package, used as a program outside the tree uses it (issue 16): installs the
# current build into a fresh prefix, builds examples/embed against it with find_package(talus)
# and runs it, runs the installed tool, and compiles and links the same example with
# `pkg-config --cflags --libs talus`. Everything runs in a fresh folder under the system's
# temporary folder, away from the repository, so neither the program's folder nor the working
# folder has data/ nearby: the data is found only where the package says it is.
#     cmake -DBUILD_DIR=build -DSOURCE_DIR=. -DCXX=c++ -DLIBDIR=lib -P tests/embed/consumer_test.cmake
# (LIBDIR: the build's CMAKE_INSTALL_LIBDIR, where the install puts the archives)
cmake_minimum_required(VERSION 3.22)
foreach(var BUILD_DIR SOURCE_DIR CXX LIBDIR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "consumer_test.cmake: -D${var}=... missing")
  endif()
endforeach()

# runs a command (a list) in `dir`, without TALUS_DATA_DIR, and fails the test with its output
# when it fails; its standard output in `out`
function(run out dir)
  execute_process(COMMAND ${CMAKE_COMMAND} -E env --unset=TALUS_DATA_DIR ${ARGN}
                  WORKING_DIRECTORY ${dir} RESULT_VARIABLE status OUTPUT_VARIABLE stdout
                  ERROR_VARIABLE stderr)
  if(NOT status EQUAL 0)
    list(JOIN ARGN " " command)
    message(FATAL_ERROR "failed (${status}): ${command}\n${stdout}\n${stderr}")
  endif()
  set(${out} "${stdout}" PARENT_SCOPE)
endfunction()

function(expect text pattern what)
  if(NOT text MATCHES "${pattern}")
    message(FATAL_ERROR "${what}: no match for '${pattern}' in:\n${text}")
  endif()
endfunction()

# a fresh folder: the system's temporary folder (TMPDIR, else /tmp) and a random name
if(DEFINED ENV{TMPDIR})
  set(tmp $ENV{TMPDIR})
else()
  set(tmp /tmp)
endif()
string(RANDOM LENGTH 10 tag)
set(work ${tmp}/talus-embed-consumer-${tag})
set(prefix ${work}/prefix)
file(REMOVE_RECURSE ${work})
file(MAKE_DIRECTORY ${work})

# the install, and the files the package promises
run(ignored ${work} ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
foreach(file bin/talus ${LIBDIR}/libtalus_embed.a ${LIBDIR}/libtalus_host.a
        ${LIBDIR}/libtalus_io.a include/talus/talus.hpp include/talus/host/error.hpp
        include/talus/digging/digging.hpp include/talus/kernels/dem_types.h
        share/talus/data/scenarios/hd27.json share/talus/data/machines/wa320.json
        ${LIBDIR}/cmake/talus/talusConfig.cmake
        ${LIBDIR}/cmake/talus/talusConfigVersion.cmake
        ${LIBDIR}/pkgconfig/talus.pc)
  if(NOT EXISTS ${prefix}/${file})
    message(FATAL_ERROR "the install has no ${file} (under ${prefix})")
  endif()
endforeach()

# the example, configured and built against the install alone, run from its own folder: 3 s of
# HD27 at D400 with its own targets, which dig into the pile
run(ignored ${work} ${CMAKE_COMMAND} -S ${SOURCE_DIR}/examples/embed -B ${work}/example
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=${CXX})
run(ignored ${work} ${CMAKE_COMMAND} --build ${work}/example)
run(out ${work} ${work}/example/talus_embed_example)
message(STATUS "find_package(talus) example:\n${out}")
expect("${out}" "HD27 at D400: [1-9][0-9]* particles" "the example's pile")
expect("${out}" "final: t=3.00 s, loaded mass [1-9][0-9]*\\.[0-9] kg" "the example's dig")

# the installed tool finds its data beside itself (bin/../share/talus/data)
run(out ${work} ${prefix}/bin/talus run --scenario flat-lift --out ${work}/run --quiet)
if(NOT EXISTS ${work}/run/summary.json)
  message(FATAL_ERROR "the installed talus wrote no ${work}/run/summary.json")
endif()

# pkg-config: the same one-file program, compiled and linked with the package's flags; the data
# folder from the package's variable (a pkg-config build tells the facade itself)
set(pc_env ${CMAKE_COMMAND} -E env PKG_CONFIG_PATH=${prefix}/${LIBDIR}/pkgconfig)
run(flags ${work} ${pc_env} pkg-config --cflags --libs talus)
run(datadir ${work} ${pc_env} pkg-config --variable=datadir talus)
string(STRIP "${flags}" flags)
string(STRIP "${datadir}" datadir)
separate_arguments(flags UNIX_COMMAND "${flags}")
run(ignored ${work} ${CXX} -std=c++17 -O1 ${SOURCE_DIR}/examples/embed/main.cpp
    "-DTALUS_INSTALL_DATA_DIR=\"${datadir}\"" ${flags} -o ${work}/pkg-config-example)
run(out ${work} ${work}/pkg-config-example flat-lift D400 1)
message(STATUS "pkg-config example:\n${out}")
expect("${out}" "final: t=1.00 s, loaded mass 3500.0 kg" "the pkg-config example's run")

file(REMOVE_RECURSE ${work})
