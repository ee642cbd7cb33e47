# docs_examples.cmake - the README's next steps and the examples of docs/library.md, taken
# from the documents themselves and run as written, so that they cannot rot (run by CTest
# as test_docs_examples, see cmake/sem_tests_library.cmake):
#   1. README: `cmake --install build --prefix /opt/sem` (into PREFIX instead of /opt/sem);
#   2. docs/library.md "From C": app.c, then the pkg-config commands (shared and static
#      builds, a box made by the installed `sem primitive`, both programs run: 6 parts, area
#      22), then the CMakeLists.txt and its commands (find_package(sem), the program run);
#   3. docs/library.md "Python": the installed package found through PYTHONPATH, and the
#      example script (a beam stepped 50 times, its deformed model saved);
#   4. README "The library": the Python lines, run from the source folder.
# Every "/opt/sem" in a block becomes PREFIX. Blocks are found by their section's heading
# and their order in it; a block that is missing fails the test with its name.
# Variables: BUILD_DIR, SOURCE_DIR, PREFIX, LIBDIR, VERSION, C_COMPILER, PYTHON (may be empty:
# the Python steps are skipped), PYTHON_DIR.

cmake_minimum_required(VERSION 3.24)

function(run what)
  execute_process(COMMAND ${ARGN} WORKING_DIRECTORY ${work} RESULT_VARIABLE rc OUTPUT_VARIABLE out
    ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${ARGN}\n${out}\n${err}")
  endif()
  set(RUN_OUTPUT "${out}${err}" PARENT_SCOPE)
endfunction()

# The text of the n-th (0-based) fenced block of language `lang` in the section that starts
# with the line `heading` of `file` (up to the next "## " heading); with a fifth argument,
# the n-th of the blocks that contain that text.
function(doc_block file heading lang n out)
  set(contains "${ARGV5}")
  file(READ ${file} text)
  string(FIND "${text}" "\n${heading}\n" at)
  if(at LESS 0)
    message(FATAL_ERROR "${file}: no section \"${heading}\"")
  endif()
  math(EXPR at "${at} + 1")
  string(SUBSTRING "${text}" ${at} -1 text)
  string(FIND "${text}" "\n## " end)
  if(end GREATER -1)
    string(SUBSTRING "${text}" 0 ${end} text)
  endif()
  set(fence "```${lang}\n")
  string(LENGTH "${fence}" fence_length)
  set(k 0)
  while(TRUE)
    string(FIND "${text}" "${fence}" start)
    if(start LESS 0)
      message(FATAL_ERROR "${file}: section \"${heading}\" has no ${lang} block number ${n} "
        "(counting those with \"${contains}\")")
    endif()
    math(EXPR start "${start} + ${fence_length}")
    string(SUBSTRING "${text}" ${start} -1 text)
    string(FIND "${text}" "```" end)
    string(SUBSTRING "${text}" 0 ${end} block)
    string(FIND "${block}" "${contains}" has)
    if(has GREATER -1)
      if(k EQUAL n)
        set(${out} "${block}" PARENT_SCOPE)
        return()
      endif()
      math(EXPR k "${k} + 1")
    endif()
    math(EXPR end "${end} + 3")
    string(SUBSTRING "${text}" ${end} -1 text)
  endwhile()
endfunction()

# A shell block with /opt/sem moved to PREFIX, written to work/NAME.sh and run there with
# sh -e (any failing command fails the test); its output in RUN_OUTPUT.
function(run_sh_block name block)
  string(REPLACE "/opt/sem/lib/" "${PREFIX}/${LIBDIR}/" block "${block}")
  string(REPLACE "/opt/sem" "${PREFIX}" block "${block}")
  file(WRITE ${work}/${name}.sh "${block}")
  run("${name}: ${block}" sh -e ${work}/${name}.sh)
  set(RUN_OUTPUT "${RUN_OUTPUT}" PARENT_SCOPE)
endfunction()

function(expect_output what pattern)
  if(NOT RUN_OUTPUT MATCHES "${pattern}")
    message(FATAL_ERROR "${what}: expected \"${pattern}\" in:\n${RUN_OUTPUT}")
  endif()
endfunction()

set(readme ${SOURCE_DIR}/README.md)
set(library ${SOURCE_DIR}/docs/library.md)
set(work ${PREFIX}-work)
file(REMOVE_RECURSE ${PREFIX} ${work})
file(MAKE_DIRECTORY ${work})
# the documents say cc and python3: the compiler and interpreter this build uses
get_filename_component(cc_dir ${C_COMPILER} DIRECTORY)
file(MAKE_DIRECTORY ${work}/bin)
file(CREATE_LINK ${C_COMPILER} ${work}/bin/cc SYMBOLIC)
if(PYTHON)
  file(CREATE_LINK ${PYTHON} ${work}/bin/python3 SYMBOLIC)
endif()
set(ENV{PATH} "${work}/bin:$ENV{PATH}")
set(ENV{CC} ${C_COMPILER})
unset(ENV{SEM_LIBRARY})
unset(ENV{PKG_CONFIG_PATH})
unset(ENV{PYTHONPATH})

# 1. README: install
doc_block(${readme} "## Two commands (fresh Debian machine, as root)" sh 0 install
  "cmake --install build --prefix /opt/sem")
string(REPLACE "cmake --install build" "\"${CMAKE_COMMAND}\" --install \"${BUILD_DIR}\"" install "${install}")
if(NOT PYTHON)
  string(REGEX REPLACE "\n[^\n]*python3[^\n]*" "" install "${install}")
endif()
run_sh_block(readme_install "${install}")
if(PYTHON)
  expect_output("README's install block" "\n${VERSION} ${PREFIX}/${LIBDIR}/libsem.so")
  message(STATUS "README, install: the Python package imports from ${PREFIX}")
endif()
if(NOT EXISTS ${PREFIX}/bin/sem OR NOT EXISTS ${PREFIX}/${LIBDIR}/libsem.so)
  message(FATAL_ERROR "README's install command did not install bin/sem and libsem.so into ${PREFIX}")
endif()

# 2. docs/library.md: C with pkg-config, then CMake
doc_block(${library} "## From C" c 0 app_c)
file(WRITE ${work}/app.c "${app_c}")
doc_block(${library} "## From C" sh 0 pkg_config)
run_sh_block(library_pkg_config "${pkg_config}")
string(REGEX MATCHALL "sem ${VERSION}: 6 parts, area 22\n" lines "${RUN_OUTPUT}")
list(LENGTH lines n_lines)
if(NOT n_lines EQUAL 2)
  message(FATAL_ERROR "docs/library.md pkg-config block: expected \"sem ${VERSION}: 6 parts, area 22\" "
    "from app and app_static, got:\n${RUN_OUTPUT}")
endif()
message(STATUS "library.md, pkg-config: app and app_static print \"sem ${VERSION}: 6 parts, area 22\"")
doc_block(${library} "## From C" cmake 0 cmakelists)
file(WRITE ${work}/CMakeLists.txt "${cmakelists}")
doc_block(${library} "## From C" sh 1 cmake_commands)
run_sh_block(library_cmake "${cmake_commands}")
expect_output("docs/library.md CMake block" "sem ${VERSION}: 6 parts, area 22\n")
message(STATUS "library.md, CMake: app prints \"sem ${VERSION}: 6 parts, area 22\"")

# 3. docs/library.md: the Python package from the prefix, and its example
if(PYTHON)
  doc_block(${library} "## Python" sh 0 python_path)
  run_sh_block(library_python_path "${python_path}")
  expect_output("docs/library.md Python block" "${VERSION} ${PREFIX}/${LIBDIR}/libsem.so")
  file(GLOB python_dir LIST_DIRECTORIES true ${PREFIX}/${LIBDIR}/python3*/dist-packages)
  if(NOT python_dir STREQUAL "${PREFIX}/${PYTHON_DIR}")
    message(FATAL_ERROR "the package is in ${PREFIX}/${PYTHON_DIR}; the documented glob finds ${python_dir}")
  endif()
  doc_block(${library} "## Python" python 0 example)
  file(WRITE ${work}/example.py "${example}")
  file(REMOVE ${work}/frame.igs)
  run("docs/library.md Python example" ${CMAKE_COMMAND} -E env PYTHONPATH=${python_dir}
    PYTHONDONTWRITEBYTECODE=1 ${PYTHON} ${work}/example.py)
  if(NOT EXISTS ${work}/frame.igs)
    message(FATAL_ERROR "docs/library.md Python example: frame.igs was not written")
  endif()
  message(STATUS "library.md, Python: the example ran with the installed package, frame.igs written")

  # 4. README: the Python lines, from the source folder (its scene path is relative to it)
  doc_block(${readme} "## The library" python 0 readme_python)
  file(WRITE ${work}/readme.py "${readme_python}")
  execute_process(COMMAND ${CMAKE_COMMAND} -E env PYTHONPATH=${python_dir} PYTHONDONTWRITEBYTECODE=1
    ${PYTHON} ${work}/readme.py WORKING_DIRECTORY ${SOURCE_DIR} RESULT_VARIABLE rc
    OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "README's Python lines failed (${rc}):\n${readme_python}\n${out}\n${err}")
  endif()
  message(STATUS "README, Python: ran with the installed package")
endif()
