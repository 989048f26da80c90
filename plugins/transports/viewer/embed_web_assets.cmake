# SPDX-License-Identifier: Apache-2.0
# Build-time script: writes OUTPUT, a C++ file holding every file of WEB_DIR as a byte array
# (see web_assets.hpp). Run by the viewer's CMakeLists.txt whenever a file of web/ changes.
file(GLOB files RELATIVE "${WEB_DIR}" "${WEB_DIR}/*")
list(SORT files)
set(arrays "")
set(entries "")
set(index 0)
foreach(name ${files})
  if(IS_DIRECTORY "${WEB_DIR}/${name}")
    continue()
  endif()
  get_filename_component(ext "${name}" LAST_EXT)
  string(TOLOWER "${ext}" ext)
  if(ext STREQUAL ".html")
    set(type "text/html; charset=utf-8")
  elseif(ext STREQUAL ".js" OR ext STREQUAL ".mjs")
    set(type "text/javascript; charset=utf-8")
  elseif(ext STREQUAL ".css")
    set(type "text/css; charset=utf-8")
  elseif(ext STREQUAL ".svg")
    set(type "image/svg+xml")
  elseif(ext STREQUAL ".png")
    set(type "image/png")
  elseif(ext STREQUAL ".ico")
    set(type "image/x-icon")
  elseif(ext STREQUAL ".json")
    set(type "application/json")
  else()
    message(FATAL_ERROR "embed_web_assets: no MIME type for ${WEB_DIR}/${name}")
  endif()
  file(READ "${WEB_DIR}/${name}" hex HEX)
  string(LENGTH "${hex}" hex_length)
  math(EXPR size "${hex_length} / 2")
  string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," bytes "${hex}")
  string(REGEX REPLACE "(0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,0x..,)" "\\1\n" bytes "${bytes}")
  string(APPEND arrays "// ${name}\nconstexpr unsigned char kFile${index}[] = {\n${bytes}0};\n\n")
  string(APPEND entries "    {\"/${name}\", \"${type}\", {reinterpret_cast<const char*>(kFile${index}), ${size}}},\n")
  math(EXPR index "${index} + 1")
endforeach()
if(index EQUAL 0)
  message(FATAL_ERROR "embed_web_assets: no files in ${WEB_DIR}")
endif()
file(WRITE "${OUTPUT}.tmp"
  "// Generated from ${WEB_DIR} by embed_web_assets.cmake; do not edit.\n"
  "#include \"web_assets.hpp\"\n\n"
  "namespace ubersim::viewer {\nnamespace {\n\n"
  "${arrays}"
  "const WebAsset kAssets[] = {\n${entries}};\n\n"
  "}  // namespace\n\n"
  "std::span<const WebAsset> WebAssets() { return kAssets; }\n\n"
  "const WebAsset* FindWebAsset(std::string_view path) {\n"
  "  if (path == \"/\") path = \"/index.html\";\n"
  "  for (const WebAsset& a : kAssets) {\n"
  "    if (a.path == path) return &a;\n"
  "  }\n"
  "  return nullptr;\n"
  "}\n\n"
  "}  // namespace ubersim::viewer\n")
execute_process(COMMAND ${CMAKE_COMMAND} -E copy_if_different "${OUTPUT}.tmp" "${OUTPUT}")
