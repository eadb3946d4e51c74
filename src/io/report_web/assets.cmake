# The chart library of the HTML report (uPlot), installed from the npm registry into the build
# tree by `npm ci` (versions pinned by the checked-in package-lock.json) and compiled into
# cncore_io as byte arrays, so that every report is one self-contained file that opens offline.
find_program(CNCORE_NPM npm)
if(NOT CNCORE_NPM)
  message(FATAL_ERROR "npm not found: the HTML report needs it to install uPlot "
                      "(Debian: apt-get install nodejs npm; `make` installs them)")
endif()
set(_web_src ${CMAKE_CURRENT_SOURCE_DIR}/report_web)
set(_web_bin ${CMAKE_CURRENT_BINARY_DIR}/report_web)
set(_uplot_dist ${_web_bin}/node_modules/uplot/dist)
add_custom_command(
  OUTPUT ${_uplot_dist}/uPlot.iife.min.js ${_uplot_dist}/uPlot.min.css
  COMMAND ${CMAKE_COMMAND} -E make_directory ${_web_bin}
  COMMAND ${CMAKE_COMMAND} -E copy ${_web_src}/package.json ${_web_src}/package-lock.json ${_web_bin}
  COMMAND ${CNCORE_NPM} ci --no-audit --no-fund --loglevel=error
  # npm keeps the files' dates from the package: touch them so that the step is not rerun.
  COMMAND ${CMAKE_COMMAND} -E touch ${_uplot_dist}/uPlot.iife.min.js ${_uplot_dist}/uPlot.min.css
  WORKING_DIRECTORY ${_web_bin}
  DEPENDS ${_web_src}/package.json ${_web_src}/package-lock.json
  COMMENT "npm ci: uPlot for the HTML report"
  VERBATIM)
set(_gen ${CMAKE_CURRENT_BINARY_DIR}/generated)
add_custom_command(
  OUTPUT ${_gen}/uplot_js.cpp
  COMMAND ${CMAKE_COMMAND} -DINPUT=${_uplot_dist}/uPlot.iife.min.js -DOUTPUT=${_gen}/uplot_js.cpp
          -DNAME=uplot_js -P ${_web_src}/embed.cmake
  DEPENDS ${_uplot_dist}/uPlot.iife.min.js ${_web_src}/embed.cmake
  VERBATIM)
add_custom_command(
  OUTPUT ${_gen}/uplot_css.cpp
  COMMAND ${CMAKE_COMMAND} -DINPUT=${_uplot_dist}/uPlot.min.css -DOUTPUT=${_gen}/uplot_css.cpp
          -DNAME=uplot_css -P ${_web_src}/embed.cmake
  DEPENDS ${_uplot_dist}/uPlot.min.css ${_web_src}/embed.cmake
  VERBATIM)
target_sources(cncore_io PRIVATE report.cpp report_html.cpp report_losses.cpp report_page.cpp report_table.cpp ${_gen}/uplot_js.cpp
  ${_gen}/uplot_css.cpp)
