# Writes a C++ source defining `std::string_view NAME()` with the bytes of INPUT (a byte array,
# so that no string-literal length limit or character-set conversion applies).
# Usage: cmake -DINPUT=file -DOUTPUT=file.cpp -DNAME=function [-DNAMESPACE=ns] -P embed.cmake
if(NOT NAMESPACE)
  set(NAMESPACE cncore::io::assets)
endif()
file(READ "${INPUT}" hex HEX)
string(LENGTH "${hex}" hex_len)
math(EXPR size "${hex_len} / 2")
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," bytes "${hex}")
# Break the one long line every 32 bytes (readable diffs of the generated file, faster compile).
string(REGEX REPLACE "((0x[0-9a-f][0-9a-f],){32})" "\\1\n" bytes "${bytes}")
file(WRITE "${OUTPUT}.tmp"
  "// Generated from ${INPUT} by embed.cmake; do not edit.\n"
  "#include <string_view>\n"
  "namespace ${NAMESPACE} {\n"
  "namespace {\n"
  "constexpr unsigned char kBytes[${size} + 1] = {\n${bytes}0};\n"
  "}  // namespace\n"
  "std::string_view ${NAME}() {\n"
  "  return {reinterpret_cast<const char*>(kBytes), ${size}};\n"
  "}\n"
  "}  // namespace ${NAMESPACE}\n")
file(RENAME "${OUTPUT}.tmp" "${OUTPUT}")
