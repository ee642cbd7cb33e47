# viewer.cmake - the browser viewer's page and script, built into the sem binary (included by
# the top-level CMakeLists.txt after the sem target; see viewer/embed.cmake).
set(SEM_VIEWER_INPUTS ${CMAKE_CURRENT_LIST_DIR}/viewer.html ${CMAKE_CURRENT_LIST_DIR}/viewer.js)
set(SEM_VIEWER_C ${CMAKE_BINARY_DIR}/generated/viewer_assets.c)
add_custom_command(
  OUTPUT ${SEM_VIEWER_C}
  COMMAND ${CMAKE_COMMAND} -E make_directory ${CMAKE_BINARY_DIR}/generated
  COMMAND ${CMAKE_COMMAND} -DOUTPUT=${SEM_VIEWER_C}
          -DINPUTS=${CMAKE_CURRENT_LIST_DIR}/viewer.html|${CMAKE_CURRENT_LIST_DIR}/viewer.js
          -DNAMES=sem_viewer_html|sem_viewer_js -P ${CMAKE_CURRENT_LIST_DIR}/embed.cmake
  DEPENDS ${SEM_VIEWER_INPUTS} ${CMAKE_CURRENT_LIST_DIR}/embed.cmake
  COMMENT "Embedding the browser viewer"
  VERBATIM)
target_sources(sem PRIVATE ${SEM_VIEWER_C})
