# SPDX-License-Identifier: Apache-2.0
# The kernel's API rules (docs/architecture.md), checked on the sources:
#  1. at most MAX_HEADERS public headers under PUBLIC_DIR, each opening (after the licence line)
#     with a comment saying what it owns;
#  2. no public header includes ODE, Boost (Boost.DLL among it), the SDK's plugin.hpp (which pulls
#     Boost.DLL in), a header of kernel/src, or anything but the standard library, the SDK and the
#     other public headers; none names an internal implementation type;
#  3. no file under SCAN_DIRS includes a private header (one that exists under PRIVATE_DIR) unless
#     it is in DOOR (path prefixes relative to ROOT: the internal door's users).
# Run as: cmake -DROOT=… -DPUBLIC_DIR=… -DPRIVATE_DIR=… -DSCAN_DIRS=a,b -DDOOR=x,y
#         -DMAX_HEADERS=12 -P check_kernel_api.cmake
# Every broken rule is printed as "file: rule"; the script fails when there is one.
cmake_minimum_required(VERSION 3.20)

set(internal_types
  WorldImpl BodyImpl GeomImpl JointImpl NodeImpl SceneGraph CollisionManager MaterialTable
  IslandStepper LoneBodyStepper PerceptionPipeline RadioLink FaultMonitor LastGoodState BodyWatch
  TransportHost RobotServices OdeLibrary OdeWorld OdeSpace OdeBody OdeGeom OdeJoint
  dWorldID dBodyID dGeomID dJointID dSpaceID dReal dContactGeom)
set(problems)
string(REPLACE "," ";" SCAN_DIRS "${SCAN_DIRS}")
string(REPLACE "," ";" DOOR "${DOOR}")

# The lines of a file as a list; characters that mean something to CMake lists are replaced
# (";" and brackets), so line numbers stay right.
function(read_lines file out)
  file(READ ${file} text)
  string(REPLACE ";" "," text "${text}")
  string(REPLACE "[" "(" text "${text}")
  string(REPLACE "]" ")" text "${text}")
  string(REPLACE "\\" "/" text "${text}")
  string(REPLACE "\n" ";" text "${text}")
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

file(GLOB_RECURSE public_headers RELATIVE ${PUBLIC_DIR} ${PUBLIC_DIR}/*.hpp ${PUBLIC_DIR}/*.h)
list(LENGTH public_headers count)
if(count GREATER MAX_HEADERS)
  list(APPEND problems "${PUBLIC_DIR}: ${count} public headers, at most ${MAX_HEADERS}")
endif()

foreach(rel ${public_headers})
  set(file ${PUBLIC_DIR}/${rel})
  read_lines(${file} lines)
  list(LENGTH lines n)
  if(n LESS 2)
    list(APPEND problems "${file}: empty")
    continue()
  endif()
  list(GET lines 1 second)
  if(NOT second MATCHES "^// [A-Z]")
    list(APPEND problems "${file}: does not open with a comment saying what it owns (line 2)")
  endif()
  set(line_no 0)
  foreach(line IN LISTS lines)
    math(EXPR line_no "${line_no} + 1")
    if(line MATCHES "^[ \t]*#[ \t]*include[ \t]*[<\"]([^>\"]+)[>\"]")
      set(inc ${CMAKE_MATCH_1})
      if(inc MATCHES "^ode/")
        list(APPEND problems "${file}:${line_no}: includes <${inc}> (ODE stays inside the kernel)")
      elseif(inc MATCHES "^boost/")
        list(APPEND problems "${file}:${line_no}: includes <${inc}> (Boost stays inside the kernel)")
      elseif(inc STREQUAL "ubersim/plugin.hpp")
        list(APPEND problems "${file}:${line_no}: includes ubersim/plugin.hpp, which pulls in Boost.DLL (use plugin_kind.hpp or plugin_descriptor.hpp)")
      elseif(EXISTS ${PRIVATE_DIR}/${inc})
        list(APPEND problems "${file}:${line_no}: includes the private header ${inc}")
      elseif(inc MATCHES "/" AND NOT inc MATCHES "^ubersim/")
        list(APPEND problems "${file}:${line_no}: includes ${inc}: only the standard library, the SDK and public kernel headers")
      endif()
    endif()
    string(REGEX REPLACE "//.*$" "" code "${line}")
    foreach(type ${internal_types})
      if(code MATCHES "(^|[^A-Za-z0-9_])${type}([^A-Za-z0-9_]|$)")
        # The PIMPL may name its implementation: declared, and held by pointer.
        if(NOT (type STREQUAL "WorldImpl" AND (code MATCHES "^class WorldImpl,$" OR code MATCHES "unique_ptr<WorldImpl>")))
          list(APPEND problems "${file}:${line_no}: names the internal type ${type}")
        endif()
      endif()
    endforeach()
  endforeach()
endforeach()

foreach(dir ${SCAN_DIRS})
  file(GLOB_RECURSE sources ${dir}/*.cpp ${dir}/*.hpp ${dir}/*.h ${dir}/*.cc)
  foreach(file ${sources})
    file(RELATIVE_PATH rel ${ROOT} ${file})
    set(in_door FALSE)
    foreach(prefix ${DOOR})
      string(FIND "${rel}" "${prefix}" at)
      if(at EQUAL 0)
        set(in_door TRUE)
      endif()
    endforeach()
    if(in_door)
      continue()
    endif()
    file(STRINGS ${file} includes REGEX "^[ \t]*#[ \t]*include[ \t]*\"")
    foreach(line IN LISTS includes)
      if(line MATCHES "\"([^\"]+)\"")
        set(inc ${CMAKE_MATCH_1})
        get_filename_component(beside ${file} DIRECTORY)
        if(EXISTS ${PRIVATE_DIR}/${inc} AND NOT EXISTS ${beside}/${inc})
          list(APPEND problems "${rel}: includes the private header ${inc} but is not one of the internal door's users")
        endif()
      endif()
    endforeach()
  endforeach()
endforeach()

if(problems)
  list(LENGTH problems np)
  string(REPLACE ";" "\n  " text "${problems}")
  message(FATAL_ERROR "the kernel's API rules are broken (${np}):\n  ${text}")
endif()
message(STATUS "kernel API rules hold: ${count} public headers")
