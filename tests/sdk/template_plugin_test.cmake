# SPDX-License-Identifier: Apache-2.0
# Driven by ctest (see CMakeLists.txt). Fails with a message at the first step that goes wrong.
# It is given the build folder and, of the source tree, only a team's own plugin (TEAM_MECANUM_SRC:
# the team's code, not ÜberSim's): everything ÜberSim provides comes from the prefix after the
# install, as it does for a team (docs/plugins.md, "Out of tree").
cmake_minimum_required(VERSION 3.22)

function(run_step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(STEP_OUTPUT "${out}${err}" PARENT_SCOPE)
endfunction()

function(require_file path what)
  if(NOT EXISTS "${path}")
    message(FATAL_ERROR "${what} is not installed: ${path} does not exist")
  endif()
endfunction()

file(REMOVE_RECURSE "${WORK_DIR}")
set(prefix "${WORK_DIR}/prefix")
set(plugin_src "${WORK_DIR}/template_drive_src")
set(plugin_build "${WORK_DIR}/template_drive")
# Only the prefix may be found: no package registries; CMAKE_PREFIX_PATH is searched before the
# system, and the ubersim_DIR checks below catch an ÜberSim found anywhere else.
set(isolated -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF -DCMAKE_FIND_USE_SYSTEM_PACKAGE_REGISTRY=OFF
    "-DCMAKE_PREFIX_PATH=${prefix}")

# 1. Install the built tree, as `cmake --install` would for a team.
run_step("install" ${CMAKE_COMMAND} --install "${UBERSIM_BUILD_DIR}" --prefix "${prefix}")

# 2. The package says where the template, the .proto files and the docs are; a project that
#    only asks find_package(ubersim) learns them (LANGUAGES NONE: no compiler check, fast).
file(WRITE "${WORK_DIR}/where/CMakeLists.txt" [=[
cmake_minimum_required(VERSION 3.22)
project(where LANGUAGES NONE)
find_package(ubersim 0.1 REQUIRED)
file(WRITE "${CMAKE_BINARY_DIR}/dirs.cmake"
  "set(ubersim_DIR [[${ubersim_DIR}]])\n"
  "set(template_dir [[${ubersim_SDK_TEMPLATE_DIR}]])\n"
  "set(proto_dir [[${ubersim_PROTO_DIR}]])\n"
  "set(doc_dir [[${ubersim_DOC_DIR}]])\n")
]=])
run_step("find_package(ubersim)" ${CMAKE_COMMAND} -S "${WORK_DIR}/where" -B "${WORK_DIR}/where/build"
         -G "${GENERATOR}" ${isolated})
include("${WORK_DIR}/where/build/dirs.cmake")
foreach(dir ubersim_DIR template_dir proto_dir doc_dir)
  string(FIND "${${dir}}" "${prefix}/" at)
  if(NOT at EQUAL 0)
    message(FATAL_ERROR "find_package(ubersim) gave ${dir} = '${${dir}}', not a folder in ${prefix}")
  endif()
endforeach()
if(NOT proto_dir STREQUAL "${prefix}/share/ubersim/proto")
  message(FATAL_ERROR "the .proto files are at ${proto_dir}, not ${prefix}/share/ubersim/proto")
endif()

# 3. The .proto files are installed and complete: a team generates its own bindings from them
#    alone (protoc fails on an import that is missing).
foreach(proto ssl_vision_wrapper ssl_vision_detection ssl_vision_geometry grsim_packet
        ssl_simulation_control ssl_simulation_robot_control ssl_simulation_synchronous)
  require_file("${proto_dir}/${proto}.proto" "the league's ${proto}.proto")
endforeach()
file(GLOB installed_protos "${proto_dir}/*.proto")
file(MAKE_DIRECTORY "${WORK_DIR}/bindings")
run_step("protoc on the installed .proto files" "${PROTOC}" -I "${proto_dir}"
         "--python_out=${WORK_DIR}/bindings" ${installed_protos})
require_file("${WORK_DIR}/bindings/ssl_vision_wrapper_pb2.py" "a binding generated from the install")

# 4. The docs are installed, the validation report with its figures among them.
foreach(doc plugins.md interfaces.md cli.md model-files.md validation/README.md)
  require_file("${doc_dir}/${doc}" "docs/${doc}")
endforeach()
file(GLOB figures "${doc_dir}/validation/*.svg")
if(NOT figures)
  message(FATAL_ERROR "docs/validation's figures are not installed in ${doc_dir}/validation")
endif()

# 5. Copy the template out of the install and build it with nothing but the installed package.
require_file("${template_dir}/drive/CMakeLists.txt" "the SDK's template plugin")
file(COPY "${template_dir}/drive/" DESTINATION "${plugin_src}")
run_step("configure template" ${CMAKE_COMMAND} -S "${plugin_src}" -B "${plugin_build}"
         -G "${GENERATOR}" ${isolated})
file(STRINGS "${plugin_build}/CMakeCache.txt" found REGEX "^ubersim_DIR:PATH=")
if(NOT found STREQUAL "ubersim_DIR:PATH=${ubersim_DIR}")
  message(FATAL_ERROR "the template found another ÜberSim (${found}), not ${ubersim_DIR}")
endif()
run_step("build template" ${CMAKE_COMMAND} --build "${plugin_build}")
if(NOT EXISTS "${plugin_build}/libubersim_template_drive.so")
  message(FATAL_ERROR "the template build produced no libubersim_template_drive.so")
endif()

# 6. The installed ubersim finds and accepts it through --plugin-path.
set(ubersim "${prefix}/bin/ubersim")
run_step("ubersim plugins" "${ubersim}" plugins --plugin-path "${plugin_build}")
if(NOT STEP_OUTPUT MATCHES "template_drive +drive +1\\.0\\.0 +0\\.1")
  message(FATAL_ERROR "ubersim plugins does not list template_drive:\n${STEP_OUTPUT}")
endif()

# 7. A world with two robots driven by it loads (its parameters checked against the plugin's
#    schema) and runs; the world names the plugin folder itself (plugin_paths). It has no
#    transports; --local-only keeps it off the network all the same.
file(WRITE "${WORK_DIR}/robot.yaml" "kind: robot\nname: template-bot\n"
  "body: {mass: 2.3, radius: 0.09, height: 0.15, front_distance: 0.07}\n"
  "drive: {plugin: template_drive, max_speed: 3.0, max_accel: 3.0}\n")
file(WRITE "${WORK_DIR}/world.yaml" "kind: world\nname: template-world\n"
  "field: ${prefix}/share/ubersim/models/fields/div-b.yaml\n"
  "ball: ${prefix}/share/ubersim/models/balls/golf.yaml\n"
  "plugin_paths: [template_drive]\n"
  "robots:\n"
  "  - {team: blue, id: 0, model: robot.yaml, x: -1.0, y: 0.0, yaw: 0.0}\n"
  "  - {team: yellow, id: 0, model: robot.yaml, x: 1.0, y: 0.0, yaw: 3.14159}\n")
run_step("ubersim run" "${ubersim}" run "${WORK_DIR}/world.yaml" --local-only --fast --duration 2 --quiet)
if(NOT STEP_OUTPUT MATCHES "2 robots" OR NOT STEP_OUTPUT MATCHES "stopped at sim time 2")
  message(FATAL_ERROR "the world with template_drive robots did not run:\n${STEP_OUTPUT}")
endif()

# 8. A typo in the plugin's block is reported with file, line, column and key; the plugin is
#    found through UBERSIM_PLUGIN_PATH this time, the third way docs/plugins.md names.
file(WRITE "${WORK_DIR}/typo-robot.yaml" "kind: robot\nname: typo-bot\n"
  "body: {mass: 2.3, radius: 0.09, height: 0.15}\n"
  "drive:\n  plugin: template_drive\n  max_sped: 3.0\n")
execute_process(COMMAND ${CMAKE_COMMAND} -E env "UBERSIM_PLUGIN_PATH=${plugin_build}"
                "${ubersim}" validate "${WORK_DIR}/typo-robot.yaml"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 3 OR NOT out MATCHES "typo-robot.yaml:6:3: .*max_sped")
  message(FATAL_ERROR "the typo was not reported as file:6:3 with the key (exit ${rc}):\n${out}${err}")
endif()
# 9. Next year's robot: a team's mecanum drive (contact wheels, rollers at 45° through
#    WheelSpec::roller_turn) built against the install alone, then checked the way docs/plugins.md
#    tells a team to: the installed `ubersim validate-physics --robot` drives it forward, fast,
#    sideways, diagonally and turning, and at its acceleration limit, against its own limits.
set(mecanum_src "${WORK_DIR}/team_mecanum_src")
set(mecanum_build "${WORK_DIR}/team_mecanum")
file(COPY "${TEAM_MECANUM_SRC}/" DESTINATION "${mecanum_src}")
run_step("configure team_mecanum" ${CMAKE_COMMAND} -S "${mecanum_src}" -B "${mecanum_build}"
         -G "${GENERATOR}" ${isolated})
run_step("build team_mecanum" ${CMAKE_COMMAND} --build "${mecanum_build}")
file(WRITE "${WORK_DIR}/team-mecanum.yaml" "kind: robot\nname: team-mecanum\n"
  "body: {mass: 2.3, radius: 0.09, height: 0.146, front_distance: 0.07, ground_clearance: 0.015,\n"
  "       center_of_mass_height: 0.05}\n"
  "drive:\n  plugin: team_mecanum\n  half_length: 0.0559\n  half_track: 0.0559\n  wheel_radius: 0.029\n"
  "  limits: {max_speed: 2.5, max_accel: 2.5, max_brake: 5.0, max_angular_speed: 8.0,\n"
  "           max_angular_accel: 40.0, max_angular_brake: 40.0}\n")
execute_process(COMMAND "${ubersim}" validate-physics --robot "${WORK_DIR}/team-mecanum.yaml"
                        --plugin-path "${mecanum_build}" --out "${WORK_DIR}/team-mecanum-report"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "validate-physics on the team's mecanum robot: exit ${rc}:\n${out}${err}")
endif()
set(out "${out}${err}")
foreach(scenario team_mecanum_steady_velocity team_mecanum_acceleration)
  if(NOT out MATCHES "ok +${scenario} [0-9]+/[0-9]+ in band")
    message(FATAL_ERROR "validate-physics did not pass ${scenario}:\n${out}")
  endif()
endforeach()
if(out MATCHES "non-holonomic")
  message(FATAL_ERROR "the mecanum drive did not move sideways:\n${out}")
endif()
file(READ "${WORK_DIR}/team-mecanum-report/README.md" report)
if(NOT report MATCHES "sideways")
  message(FATAL_ERROR "the report has no sideways case:\n${report}")
endif()
# The report describes the team's robot, not a shipped one.
if(NOT report MATCHES "The robot team-mecanum \\(" OR report MATCHES "wheels at 60°")
  message(FATAL_ERROR "the report does not describe the team's robot:\n${report}")
endif()
message(STATUS "installed: package, template, .proto files and docs; template copied from the "
               "install, built against it alone, listed, run and validated; a team's mecanum "
               "drive built from the install and validated by the installed validate-physics")
