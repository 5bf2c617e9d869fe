// The HTML report page's own script and style (viewer.js, viewer.css in this folder), compiled
// into the library by embed_assets.cmake so that the binary needs no share folder.
#pragma once

namespace vdbwrap::report {

extern const char* const kViewerJs;
extern const char* const kViewerCss;

}  // namespace vdbwrap::report
