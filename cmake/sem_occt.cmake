# sem_occt.cmake - STEP files through Open CASCADE (Debian: libocct-*-dev 7.6).
#
# SEM_WITH_OCCT (ON when Open CASCADE is found) compiles src/io/step_occt.cpp, the one C++
# file of libsem, behind the C functions sem_step_read / sem_step_write (sem/model.h).
# Without it those functions report that STEP is not compiled in (src/io/step_stub.c) and
# everything else builds and runs as before. Sets SEM_OCCT_LIBS (full paths) for the
# install rules and the Open CASCADE test programs, and SEM_HAS_STEP (0/1).

set(SEM_OCCT_TOOLKITS TKernel TKMath TKG2d TKG3d TKGeomBase TKBRep TKGeomAlgo TKTopAlgo
  TKShHealing TKXSBase TKSTEPBase TKSTEPAttr TKSTEP209 TKSTEP)
find_path(OCCT_INCLUDE_DIR Standard_Version.hxx PATH_SUFFIXES opencascade)
set(SEM_OCCT_FOUND FALSE)
if(OCCT_INCLUDE_DIR)
  set(SEM_OCCT_FOUND TRUE)
  set(SEM_OCCT_LIBS "")
  foreach(tk ${SEM_OCCT_TOOLKITS})
    find_library(OCCT_${tk}_LIB ${tk})
    if(OCCT_${tk}_LIB)
      list(APPEND SEM_OCCT_LIBS ${OCCT_${tk}_LIB})
    else()
      set(SEM_OCCT_FOUND FALSE)
    endif()
  endforeach()
endif()
include(CheckLanguage)
check_language(CXX)
if(NOT CMAKE_CXX_COMPILER)
  set(SEM_OCCT_FOUND FALSE)
endif()

option(SEM_WITH_OCCT "Read and write STEP files through Open CASCADE" ${SEM_OCCT_FOUND})
set(SEM_HAS_STEP 0)
if(SEM_WITH_OCCT)
  if(NOT SEM_OCCT_FOUND)
    message(FATAL_ERROR "SEM_WITH_OCCT is ON but Open CASCADE (headers, ${SEM_OCCT_TOOLKITS}) "
      "or a C++ compiler was not found; install libocct-data-exchange-dev "
      "libocct-modeling-algorithms-dev or configure with -DSEM_WITH_OCCT=OFF")
  endif()
  enable_language(CXX)
  set(CMAKE_CXX_STANDARD 17)
  set(CMAKE_CXX_STANDARD_REQUIRED ON)
  set(CMAKE_CXX_EXTENSIONS OFF)
  set(SEM_HAS_STEP 1)
  # The C++ objects join semlib as plain objects, so that the static library (and the
  # installed sem::sem_static) does not make every C program that links it a C++ link:
  # libstdc++ is named instead, privately, like every other dependency.
  add_library(sem_step_occt OBJECT src/io/step_occt.cpp)
  set_target_properties(sem_step_occt PROPERTIES POSITION_INDEPENDENT_CODE ON)
  target_include_directories(sem_step_occt PRIVATE include ${CMAKE_BINARY_DIR}/include src)
  target_include_directories(sem_step_occt SYSTEM PRIVATE ${OCCT_INCLUDE_DIR})
  target_compile_definitions(sem_step_occt PRIVATE SEM_HAVE_OCCT=1)
  target_sources(semlib PRIVATE $<TARGET_OBJECTS:sem_step_occt>)
  target_compile_definitions(semlib PRIVATE SEM_HAVE_OCCT=1)
  target_link_libraries(semlib PRIVATE ${SEM_OCCT_LIBS} stdc++)
  message(STATUS "sem: STEP support through Open CASCADE (${OCCT_INCLUDE_DIR})")
else()
  message(STATUS "sem: STEP support off (Open CASCADE not found or SEM_WITH_OCCT=OFF)")
endif()
