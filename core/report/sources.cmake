# The HTML report (core/report), included by core/CMakeLists.txt. The page's own script and
# style are compiled into the library (embed_assets.cmake); three.js is read at run time.
set(VDBWRAP_PAGE_ASSETS ${CMAKE_CURRENT_BINARY_DIR}/report/page_assets.cpp)
add_custom_command(OUTPUT ${VDBWRAP_PAGE_ASSETS}
  COMMAND ${CMAKE_COMMAND} -DJS=${CMAKE_CURRENT_SOURCE_DIR}/report/viewer.js
          -DCSS=${CMAKE_CURRENT_SOURCE_DIR}/report/viewer.css -DOUT=${VDBWRAP_PAGE_ASSETS}
          -P ${CMAKE_CURRENT_SOURCE_DIR}/report/embed_assets.cmake
  DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/report/viewer.js ${CMAKE_CURRENT_SOURCE_DIR}/report/viewer.css
          ${CMAKE_CURRENT_SOURCE_DIR}/report/embed_assets.cmake
  COMMENT "Embedding the HTML report's viewer script and style")
target_sources(vdbwrap_core PRIVATE
  report/html_report.cpp
  report/display_mesh.cpp
  report/input_marks.cpp
  report/three_js_path.cpp
  ${VDBWRAP_PAGE_ASSETS})
set(VDBWRAP_THREE_JS "" CACHE FILEPATH "three.min.js for HTML reports, tried before Debian's libjs-three paths")
set_property(SOURCE report/three_js_path.cpp APPEND PROPERTY COMPILE_DEFINITIONS "VDBWRAP_THREE_JS_PATH=\"${VDBWRAP_THREE_JS}\"")
