# sem_blender.cmake - the Blender add-on (blender/sem_blender, docs/blender.md).
#
# build/sem_blender.zip is the file Blender's Edit > Preferences > Add-ons > Install takes
# (a folder sem_blender/ with the add-on's modules); `cmake --install` puts it in
# share/sem/sem_blender.zip. test_blender (tests/blender/run.sh) installs sem into a fresh
# prefix and that zip into Debian's blender, headless, and compares its simulation with
# `sem run`'s (registered in cmake/sem_tests_library.cmake).

file(GLOB SEM_BLENDER_SOURCES CONFIGURE_DEPENDS ${CMAKE_SOURCE_DIR}/blender/sem_blender/*.py)
set(SEM_BLENDER_ZIP ${CMAKE_BINARY_DIR}/sem_blender.zip)
set(SEM_BLENDER_MEMBERS "")
foreach(source ${SEM_BLENDER_SOURCES})
  get_filename_component(name ${source} NAME)
  list(APPEND SEM_BLENDER_MEMBERS sem_blender/${name})
endforeach()
add_custom_command(OUTPUT ${SEM_BLENDER_ZIP}
  COMMAND ${CMAKE_COMMAND} -E rm -f ${SEM_BLENDER_ZIP}
  COMMAND ${CMAKE_COMMAND} -E tar cf ${SEM_BLENDER_ZIP} --format=zip ${SEM_BLENDER_MEMBERS}
  WORKING_DIRECTORY ${CMAKE_SOURCE_DIR}/blender
  DEPENDS ${SEM_BLENDER_SOURCES}
  COMMENT "Blender add-on: sem_blender.zip")
add_custom_target(blender_addon ALL DEPENDS ${SEM_BLENDER_ZIP})
install(FILES ${SEM_BLENDER_ZIP} DESTINATION ${CMAKE_INSTALL_DATADIR}/sem)

