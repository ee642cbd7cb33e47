# sem_tests_library.cmake - tests of sem as a library others build on (CTest):
#   test_install        install into build/install-test, build tests/install/consumer.c with
#                       pkg-config and with find_package(sem), run them, and import the
#                       installed Python package
#   test_docs_examples  the README's next steps and docs/library.md's C, CMake and Python
#                       examples, extracted from the documents and run against an install
#   test_python         the Python package's pytest suite (python/tests)
#   test_blender        the Blender add-on, headless (tests/blender/run.sh)
#   test_python_example examples/python/energies.py: a scene stepped, energies plotted
#   test_occt_*         Open CASCADE as an independent reader (tests/occt_check.cpp)
# The install and Python tests need unsanitized code (a plain program or python3 cannot
# load an AddressSanitizer libsem), so a SEM_SANITIZE build leaves them out; the C tests
# cover the same library code there.

if(NOT SEM_SANITIZE)
  add_test(NAME test_install COMMAND ${CMAKE_COMMAND}
    -DBUILD_DIR=${CMAKE_BINARY_DIR} -DSOURCE_DIR=${CMAKE_SOURCE_DIR}
    -DPREFIX=${CMAKE_BINARY_DIR}/install-test -DLIBDIR=${CMAKE_INSTALL_LIBDIR}
    -DSOVERSION=${SEM_SOVERSION} -DVERSION=${PROJECT_VERSION} -DC_COMPILER=${CMAKE_C_COMPILER}
    -DPKG_CONFIG=${PKG_CONFIG_EXECUTABLE} -DPYTHON=${SEM_PYTHON_FOUND}
    -DPYTHON_DIR=${SEM_PYTHON_INSTALL_DIR}
    -P ${CMAKE_SOURCE_DIR}/tests/install/install_test.cmake)
  set_tests_properties(test_install PROPERTIES TIMEOUT 300 ENVIRONMENT "OMP_NUM_THREADS=2")
  # the README's next steps and docs/library.md's examples, extracted and run as written
  add_test(NAME test_docs_examples COMMAND ${CMAKE_COMMAND}
    -DBUILD_DIR=${CMAKE_BINARY_DIR} -DSOURCE_DIR=${CMAKE_SOURCE_DIR}
    -DPREFIX=${CMAKE_BINARY_DIR}/docs-install -DLIBDIR=${CMAKE_INSTALL_LIBDIR}
    -DVERSION=${PROJECT_VERSION} -DC_COMPILER=${CMAKE_C_COMPILER} -DPYTHON=${SEM_PYTHON_FOUND}
    -DPYTHON_DIR=${SEM_PYTHON_INSTALL_DIR}
    -P ${CMAKE_SOURCE_DIR}/tests/install/docs_examples.cmake)
  set_tests_properties(test_docs_examples PROPERTIES TIMEOUT 300 ENVIRONMENT "OMP_NUM_THREADS=2")

  if(SEM_PYTHON_FOUND)
    set(python_env "SEM_LIBRARY=$<TARGET_FILE:sem_shared>" "PYTHONPATH=${CMAKE_SOURCE_DIR}/python"
      "PYTHONDONTWRITEBYTECODE=1" "SEM_SHARED_MODELS=${SEM_SHARED_MODELS}"
      "SEM_TEST_OUTPUT=${CMAKE_BINARY_DIR}/python-test-output" "SEM_SOURCE_DIR=${CMAKE_SOURCE_DIR}"
      "OMP_NUM_THREADS=2" "MPLBACKEND=Agg")
    if(TARGET sem)
      list(APPEND python_env "SEM_BINARY=$<TARGET_FILE:sem>")
    endif()
    add_test(NAME test_python COMMAND ${SEM_PYTHON_FOUND} -m pytest -q -p no:cacheprovider
      ${CMAKE_SOURCE_DIR}/python/tests)
    set_tests_properties(test_python PROPERTIES TIMEOUT 600 ENVIRONMENT "${python_env}")
    execute_process(COMMAND ${SEM_PYTHON_FOUND} -c "import matplotlib" RESULT_VARIABLE rc
      OUTPUT_QUIET ERROR_QUIET)
    if(rc EQUAL 0)
      add_test(NAME test_python_example COMMAND ${SEM_PYTHON_FOUND}
        ${CMAKE_SOURCE_DIR}/examples/python/energies.py --frames 8
        --out ${CMAKE_BINARY_DIR}/python-example)
      set_tests_properties(test_python_example PROPERTIES TIMEOUT 300 ENVIRONMENT "${python_env}")
    else()
      message(STATUS "sem: matplotlib missing; test_python_example skipped (Debian: python3-matplotlib)")
    endif()
  endif()

  # the Blender add-on in Debian's blender, headless, against a fresh install (its zip, the
  # Python package, libsem, the command); reported as skipped (77) only without blender
  if(TARGET sem)
    add_test(NAME test_blender COMMAND sh ${CMAKE_SOURCE_DIR}/tests/blender/run.sh
      ${CMAKE_COMMAND} ${CMAKE_BINARY_DIR} ${SEM_PYTHON_INSTALL_DIR} ${SEM_SHARED_MODELS}
      ${CMAKE_BINARY_DIR}/blender-test)
    set_tests_properties(test_blender PROPERTIES TIMEOUT 300 SKIP_RETURN_CODE 77
      ENVIRONMENT "OMP_NUM_THREADS=2")
  endif()
endif()

# Open CASCADE against sem's IGES and STEP, both ways (tests/occt_check.cpp)
set(SEM_OCCT_TEST_ENV "")
if(SEM_WITH_OCCT AND SEM_SANITIZE)
  # Open CASCADE's never-freed singletons are not our leaks (tests/lsan_occt.supp)
  set(SEM_OCCT_TEST_ENV
    "LSAN_OPTIONS=suppressions=${CMAKE_SOURCE_DIR}/tests/lsan_occt.supp:print_suppressions=0")
  if(TEST test_step)
    set_tests_properties(test_step PROPERTIES ENVIRONMENT "OMP_NUM_THREADS=2;${SEM_OCCT_TEST_ENV}")
  endif()
endif()
if(SEM_WITH_OCCT)
  find_library(OCCT_TKIGES_LIB TKIGES)
  find_library(OCCT_TKPRIM_LIB TKPrim)
  find_library(OCCT_TKBO_LIB TKBO)
  find_library(OCCT_TKMESH_LIB TKMesh)
  if(OCCT_TKIGES_LIB AND OCCT_TKPRIM_LIB AND OCCT_TKBO_LIB AND OCCT_TKMESH_LIB)
    add_executable(occt_check tests/occt_check.cpp)
    target_include_directories(occt_check PRIVATE src)
    target_include_directories(occt_check SYSTEM PRIVATE ${OCCT_INCLUDE_DIR})
    target_link_libraries(occt_check PRIVATE semlib ${OCCT_TKIGES_LIB} ${OCCT_TKPRIM_LIB}
      ${OCCT_TKBO_LIB} ${OCCT_TKMESH_LIB} ${SEM_OCCT_LIBS})
    # A sanitized build runs the STEP and model-space checks (they exercise step_occt.cpp and
    # the trim projection); reading every shared model twice more is left to Release, where
    # test_iges_read already loads them all under the sanitizers.
    set(modes step modelspace)
    if(NOT SEM_SANITIZE)
      list(APPEND modes written direct)
    endif()
    foreach(mode ${modes})
      add_test(NAME test_occt_${mode} COMMAND occt_check ${mode} ${SEM_SHARED_MODELS}
        ${CMAKE_BINARY_DIR}/occt-check-${mode})
      set_tests_properties(test_occt_${mode} PROPERTIES TIMEOUT 600
        ENVIRONMENT "OMP_NUM_THREADS=2;${SEM_OCCT_TEST_ENV}")
    endforeach()
    # Every shared model and the reader's own files of issue 29, read by sem and by Open
    # CASCADE: faces, each face's area (0.1 %), the box (docs/validation.md, 3d). The public
    # corpus runs the same check from scripts/corpus_reference.sh.
    if(NOT SEM_SANITIZE)
      set(reference_files)
      foreach(f unbounded_planes seams model_space model_space_near brep revolution tabulated
                bptr0 delims unknown)
        list(APPEND reference_files ${CMAKE_SOURCE_DIR}/tests/data/iges_${f}.igs)
      endforeach()
      add_test(NAME test_occt_reference COMMAND occt_check reference ${SEM_SHARED_MODELS}
        ${reference_files})
      set_tests_properties(test_occt_reference PROPERTIES TIMEOUT 900
        ENVIRONMENT "OMP_NUM_THREADS=2;${SEM_OCCT_TEST_ENV}")
    endif()
  else()
    message(STATUS "sem: TKIGES, TKPrim, TKBO or TKMesh not found; the Open CASCADE checks are skipped")
  endif()
endif()
