# tests.cmake - the suite's tests that run in JavaScript (included by CMakeLists.txt):
#   gltf_validator  the Khronos glTF-Validator on animation.glb files of sem run
#   viewer_browser  the page of sem view in headless Chromium
# Each is skipped (CTest "Skipped", exit 77) only when its tools are not installed;
# scripts/setup.sh installs them and scripts/test.sh installs the validator (npm ci).
if(TARGET sem)
  add_test(NAME gltf_validator
           COMMAND bash ${CMAKE_CURRENT_LIST_DIR}/gltf_validator_test.sh $<TARGET_FILE:sem> ${CMAKE_BINARY_DIR}/js_gltf_validator)
  add_test(NAME viewer_browser
           COMMAND bash ${CMAKE_CURRENT_LIST_DIR}/viewer_browser_test.sh $<TARGET_FILE:sem> ${CMAKE_BINARY_DIR}/js_viewer_browser)
  set_tests_properties(gltf_validator viewer_browser PROPERTIES SKIP_RETURN_CODE 77 TIMEOUT 300
                       ENVIRONMENT "OMP_NUM_THREADS=2")
endif()
