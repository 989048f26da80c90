# SPDX-License-Identifier: Apache-2.0
# Runs the key-table check (cmake/plugin_key_tables.cmake) on a copy of docs/model-files.md broken
# on purpose, made now from the doc as it is (so it follows the doc without a reconfigure):
#   BREAK=edit_row      the first row of PLUGIN's table gets its key renamed, as a hand edit would;
#   BREAK=drop_markers  PLUGIN's begin and end markers are removed.
# The check's failure message is this script's output (the test matches it).
# Run as: cmake -DROOT=<source dir> -DWORK_DIR=<dir> -DPLUGIN=<id> -DBREAK=<how> -P check_broken_doc.cmake
cmake_minimum_required(VERSION 3.19)

file(READ "${ROOT}/docs/model-files.md" doc)
set(begin "<!-- plugin-keys:${PLUGIN}:begin -->\n")
set(end "<!-- plugin-keys:${PLUGIN}:end -->\n")
string(FIND "${doc}" "${begin}" b)
if(b EQUAL -1)
  message(FATAL_ERROR "check_broken_doc: docs/model-files.md has no section for plugin '${PLUGIN}' to break")
endif()
if(BREAK STREQUAL "edit_row")
  string(SUBSTRING "${doc}" ${b} -1 section)
  string(FIND "${section}" "\n| `" row)   # the first row below the header (the header is "| key |")
  if(row EQUAL -1)
    message(FATAL_ERROR "check_broken_doc: the '${PLUGIN}' section has no table row to edit")
  endif()
  math(EXPR at "${b} + ${row} + 4")     # after the newline, "| `"
  string(SUBSTRING "${doc}" 0 ${at} head)
  string(SUBSTRING "${doc}" ${at} -1 tail)
  set(doc "${head}edited_by_hand_${tail}")
elseif(BREAK STREQUAL "drop_markers")
  string(REPLACE "${begin}" "" doc "${doc}")
  string(REPLACE "${end}" "" doc "${doc}")
else()
  message(FATAL_ERROR "check_broken_doc: BREAK must be edit_row or drop_markers, not '${BREAK}'")
endif()

set(DOC "${WORK_DIR}/model-files-${BREAK}.md")
file(WRITE "${DOC}" "${doc}")
set(MODE check)
include("${ROOT}/cmake/plugin_key_tables.cmake")
# Reached only when the check passed on the broken copy: no failure message, so the test fails.
message(STATUS "check_broken_doc: the check passed on ${DOC}, which was broken on purpose")
