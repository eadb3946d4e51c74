# `make install` and `make package`: the cncore command, its man page and shell completions
# (generated from the binary's own help texts by tools/gen-manual.sh), the documentation and the
# examples; CPack turns the same install into a Debian package, cncore_VERSION_amd64.deb.
include(GNUInstallDirs)

set(_manual_dir ${CMAKE_CURRENT_BINARY_DIR}/manual)
add_custom_command(
  OUTPUT ${_manual_dir}/cncore.1 ${_manual_dir}/cncore.bash ${_manual_dir}/_cncore
  COMMAND bash ${PROJECT_SOURCE_DIR}/tools/gen-manual.sh $<TARGET_FILE:cncore> ${_manual_dir}
  DEPENDS cncore ${PROJECT_SOURCE_DIR}/tools/gen-manual.sh
  COMMENT "man page and shell completions from cncore --help"
  VERBATIM)
add_custom_target(cncore_manual ALL
  DEPENDS ${_manual_dir}/cncore.1 ${_manual_dir}/cncore.bash ${_manual_dir}/_cncore)

install(TARGETS cncore RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(FILES ${_manual_dir}/cncore.1 DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
install(FILES ${_manual_dir}/cncore.bash DESTINATION ${CMAKE_INSTALL_DATADIR}/bash-completion/completions
        RENAME cncore)
install(FILES ${_manual_dir}/_cncore DESTINATION ${CMAKE_INSTALL_DATADIR}/zsh/vendor-completions)
install(FILES ${PROJECT_SOURCE_DIR}/README.md DESTINATION ${CMAKE_INSTALL_DOCDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR}/docs)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/examples/ DESTINATION ${CMAKE_INSTALL_DOCDIR}/examples)

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME cncore)
set(CPACK_PACKAGE_VENDOR "cncore")
set(CPACK_PACKAGE_CONTACT "cncore maintainers <cncore@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "CNC numerical-control kernel: G-code, look-ahead feed planning, interpolation (simulated)")
set(CPACK_PACKAGE_INSTALL_DIRECTORY cncore)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES TRUE)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # cncore_VERSION_ARCH.deb
set(CPACK_DEBIAN_PACKAGE_SECTION science)
# The shared libraries the binary links (fmt, muParser, the C++ runtime) as Depends, found by
# dpkg-shlibdeps (dpkg-dev); libpng and zlib are linked statically.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
include(CPack)
