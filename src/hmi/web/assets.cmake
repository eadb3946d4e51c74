# The page (index.html, app.js, …) and its libraries from the npm registry (three.js, uPlot;
# `npm ci` into the build tree, versions pinned by the checked-in package-lock.json), compiled
# into cncore_hmi as byte arrays by the report's embed.cmake: the page needs no files at run
# time and opens without a network.
find_program(CNCORE_NPM npm)
if(NOT CNCORE_NPM)
  message(FATAL_ERROR "npm not found: the web page needs it to install three.js and uPlot "
                      "(Debian: apt-get install nodejs npm; `make` installs them)")
endif()
set(_hmi_src ${CMAKE_CURRENT_SOURCE_DIR}/web)
set(_hmi_bin ${CMAKE_CURRENT_BINARY_DIR}/web)
set(_modules ${_hmi_bin}/node_modules)
set(_vendor
  three_js ${_modules}/three/build/three.module.min.js
  orbit_controls_js ${_modules}/three/examples/jsm/controls/OrbitControls.js
  uplot_js ${_modules}/uplot/dist/uPlot.iife.min.js
  uplot_css ${_modules}/uplot/dist/uPlot.min.css)
set(_vendor_files)
foreach(_i RANGE 1 7 2)
  list(GET _vendor ${_i} _f)
  list(APPEND _vendor_files ${_f})
endforeach()
add_custom_command(
  OUTPUT ${_vendor_files}
  COMMAND ${CMAKE_COMMAND} -E make_directory ${_hmi_bin}
  COMMAND ${CMAKE_COMMAND} -E copy ${_hmi_src}/package.json ${_hmi_src}/package-lock.json ${_hmi_bin}
  COMMAND ${CNCORE_NPM} ci --no-audit --no-fund --loglevel=error
  # npm keeps the files' dates from the package: touch them so that the step is not rerun.
  COMMAND ${CMAKE_COMMAND} -E touch ${_vendor_files}
  WORKING_DIRECTORY ${_hmi_bin}
  DEPENDS ${_hmi_src}/package.json ${_hmi_src}/package-lock.json
  COMMENT "npm ci: three.js and uPlot for the web page"
  VERBATIM)
set(_embed ${PROJECT_SOURCE_DIR}/src/io/report_web/embed.cmake)
set(_gen ${CMAKE_CURRENT_BINARY_DIR}/generated)
set(_assets
  index_html ${_hmi_src}/index.html
  app_js ${_hmi_src}/app.js
  view3d_js ${_hmi_src}/view3d.js
  plots_js ${_hmi_src}/plots.js
  style_css ${_hmi_src}/style.css
  ${_vendor})
list(LENGTH _assets _n)
math(EXPR _last "${_n} - 1")
foreach(_i RANGE 0 ${_last} 2)
  list(GET _assets ${_i} _name)
  math(EXPR _j "${_i} + 1")
  list(GET _assets ${_j} _file)
  add_custom_command(
    OUTPUT ${_gen}/${_name}.cpp
    COMMAND ${CMAKE_COMMAND} -DINPUT=${_file} -DOUTPUT=${_gen}/${_name}.cpp -DNAME=${_name}
            -DNAMESPACE=cncore::hmi::assets -P ${_embed}
    DEPENDS ${_file} ${_embed}
    VERBATIM)
  target_sources(cncore_hmi PRIVATE ${_gen}/${_name}.cpp)
endforeach()
