# Writes OUT: a C++ file defining vdbwrap::report::kViewerJs and kViewerCss as raw string
# literals with the text of JS and CSS (run as cmake -DJS=... -DCSS=... -DOUT=... -P).
file(READ "${JS}" js_text)
file(READ "${CSS}" css_text)
set(delimiter "vdbwrap_asset")
string(FIND "${js_text}${css_text}" ")${delimiter}\"" clash)
if(NOT clash EQUAL -1)
  message(FATAL_ERROR "embed_assets: the assets contain the raw string's delimiter )${delimiter}\"")
endif()
file(WRITE "${OUT}.tmp"
  "// Generated from core/report/viewer.js and viewer.css by embed_assets.cmake; do not edit.\n"
  "#include \"report/page_assets.h\"\n"
  "namespace vdbwrap::report {\n"
  "const char* const kViewerJs = R\"${delimiter}(${js_text})${delimiter}\";\n"
  "const char* const kViewerCss = R\"${delimiter}(${css_text})${delimiter}\";\n"
  "}  // namespace vdbwrap::report\n")
# Only a changed file is replaced: the library is not recompiled for nothing.
configure_file("${OUT}.tmp" "${OUT}" COPYONLY)
file(REMOVE "${OUT}.tmp")
