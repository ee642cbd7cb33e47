# install_test.cmake - `cmake --install` into a fresh prefix, then use the installed copy
# the way another project would (run by CTest as test_install, see
# cmake/sem_tests_library.cmake):
#   1. every promised file is there (command, shared + static library with its SONAME,
#      headers, sem.pc, semConfig.cmake / semConfigVersion.cmake, sem.1);
#   2. tests/install/consumer.c builds with `pkg-config --cflags --libs sem` (which must
#      name -lsem only: third-party libraries are private) and runs;
#   3. the same program builds with find_package(sem) against sem::sem and sem::sem_static
#      and both run;
#   4. the installed command runs, and its manual page documents every command it lists;
#      sem validate finds its installed scripts (share/sem/fem).
#   5. the installed Python package imports with no settings (SEM_LIBRARY unset): it finds
#      the shared library installed beside it.
# Variables: BUILD_DIR, SOURCE_DIR, PREFIX, LIBDIR, SOVERSION, VERSION, C_COMPILER,
# PKG_CONFIG, PYTHON (may be empty: step 5 is skipped), PYTHON_DIR.

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${ARGN}\n${out}\n${err}")
  endif()
  set(RUN_OUTPUT "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE ${PREFIX})
run("cmake --install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${PREFIX})

# 1. files
set(lib ${PREFIX}/${LIBDIR})
foreach(f bin/sem ${LIBDIR}/libsem.so ${LIBDIR}/libsem.so.${SOVERSION} ${LIBDIR}/libsem.so.${VERSION}
    ${LIBDIR}/libsem.a include/sem/sem.h include/sem/version.h include/sem/model.h
    ${LIBDIR}/pkgconfig/sem.pc ${LIBDIR}/cmake/sem/semConfig.cmake
    ${LIBDIR}/cmake/sem/semConfigVersion.cmake share/man/man1/sem.1
    share/sem/fem/validate.py share/sem/fem/fem_common.py)
  if(NOT EXISTS ${PREFIX}/${f})
    message(FATAL_ERROR "not installed: ${PREFIX}/${f}")
  endif()
endforeach()
# the benchmark helpers are not part of the installed API
if(EXISTS ${PREFIX}/include/sem/validation.h OR EXISTS ${PREFIX}/include/bench)
  message(FATAL_ERROR "benchmark headers were installed")
endif()
file(READ ${PREFIX}/include/sem/version.h version_h)
if(NOT version_h MATCHES "#define SEM_VERSION_STRING \"${VERSION}\"")
  message(FATAL_ERROR "include/sem/version.h does not say ${VERSION}")
endif()

# 2. pkg-config
set(ENV{PKG_CONFIG_PATH} ${lib}/pkgconfig)
run("pkg-config --modversion" ${PKG_CONFIG} --modversion sem)
string(STRIP "${RUN_OUTPUT}" pc_version)
if(NOT pc_version STREQUAL VERSION)
  message(FATAL_ERROR "pkg-config --modversion sem: ${pc_version}, expected ${VERSION}")
endif()
run("pkg-config --libs" ${PKG_CONFIG} --libs sem)
string(STRIP "${RUN_OUTPUT}" pc_libs)
separate_arguments(pc_libs UNIX_COMMAND "${pc_libs}")
foreach(flag ${pc_libs})
  if(flag MATCHES "^-l" AND NOT flag STREQUAL "-lsem")
    message(FATAL_ERROR "pkg-config --libs sem names ${flag}: third-party libraries must be private")
  endif()
endforeach()
run("pkg-config --cflags" ${PKG_CONFIG} --cflags sem)
string(STRIP "${RUN_OUTPUT}" pc_cflags)
separate_arguments(pc_cflags UNIX_COMMAND "${pc_cflags}")
set(work ${PREFIX}-work)
file(REMOVE_RECURSE ${work})
file(MAKE_DIRECTORY ${work})
run("cc with pkg-config" ${C_COMPILER} -std=c11 -Wall -Wextra -Werror ${pc_cflags}
  ${SOURCE_DIR}/tests/install/consumer.c -o ${work}/consumer_pc ${pc_libs} -lm
  -Wl,-rpath,${lib})
run("consumer built with pkg-config" ${work}/consumer_pc)
message(STATUS "pkg-config: ${RUN_OUTPUT}")

# 3. find_package(sem)
run("configure the find_package consumer" ${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/install
  -B ${work}/cmake -DCMAKE_PREFIX_PATH=${PREFIX} -DCMAKE_C_COMPILER=${C_COMPILER}
  -DSEM_EXPECTED_VERSION=${VERSION} -DCMAKE_BUILD_TYPE=Release)
run("build the find_package consumer" ${CMAKE_COMMAND} --build ${work}/cmake)
run("consumer built with find_package (shared)" ${work}/cmake/consumer_shared)
message(STATUS "find_package sem::sem: ${RUN_OUTPUT}")
run("consumer built with find_package (static)" ${work}/cmake/consumer_static)
message(STATUS "find_package sem::sem_static: ${RUN_OUTPUT}")

# 4. the command and its manual page
run("installed sem --help" ${PREFIX}/bin/sem --help)
string(REGEX MATCHALL "\n  [a-z]+ " commands "${RUN_OUTPUT}")
file(READ ${PREFIX}/share/man/man1/sem.1 man)
list(LENGTH commands n_commands)
if(n_commands LESS 5)
  message(FATAL_ERROR "sem --help lists ${n_commands} commands:\n${RUN_OUTPUT}")
endif()
foreach(c ${commands})
  string(STRIP "${c}" c)
  if(NOT man MATCHES "\n\\.SS ${c}[ \n]")
    message(FATAL_ERROR "sem.1 has no section (.SS ${c}) for the command ${c}")
  endif()
endforeach()
message(STATUS "installed into ${PREFIX}: ${n_commands} commands documented in sem.1")

# sem validate runs the installed tools/fem scripts (share/sem/fem, found from bin/sem), which
# import each other: a missing model is its one-line error (exit 1) before any FEM work
foreach(how installed-sem python3-script)
  if(how STREQUAL "installed-sem")
    set(cmd ${PREFIX}/bin/sem validate ${work}/missing.igs --no-install)
  else()
    set(cmd python3 ${PREFIX}/share/sem/fem/validate.py --sem ${PREFIX}/bin/sem ${work}/missing.igs --no-install)
  endif()
  execute_process(COMMAND ${cmd} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 1 OR NOT err MATCHES "^sem: [^\n]*missing.igs: cannot open[^\n]*\n$")
    message(FATAL_ERROR "sem validate (${how}) on a missing file: exit ${rc}, stderr:\n${err}")
  endif()
endforeach()

# 5. the Python package
if(PYTHON)
  run("installed Python package" ${CMAKE_COMMAND} -E env --unset=SEM_LIBRARY
    PYTHONPATH=${PREFIX}/${PYTHON_DIR} PYTHONDONTWRITEBYTECODE=1
    ${PYTHON} ${SOURCE_DIR}/tests/install/check_python.py ${PREFIX} ${VERSION})
  message(STATUS "python: ${RUN_OUTPUT}")
endif()
