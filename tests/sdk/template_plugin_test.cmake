# SPDX-License-Identifier: Apache-2.0
# Driven by ctest (see CMakeLists.txt). Fails with a message at the first step that goes wrong.
cmake_minimum_required(VERSION 3.22)

function(run_step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(STEP_OUTPUT "${out}${err}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE "${WORK_DIR}")
set(prefix "${WORK_DIR}/prefix")
set(plugin_build "${WORK_DIR}/template_drive")

# 1. Install the built tree, as `cmake --install` would for a team.
run_step("install" ${CMAKE_COMMAND} --install "${UBERSIM_BUILD_DIR}" --prefix "${prefix}")

# 2. Configure and build the template with nothing but the installed package.
run_step("configure template" ${CMAKE_COMMAND} -S "${UBERSIM_SOURCE_DIR}/sdk/template/drive"
         -B "${plugin_build}" -G "${GENERATOR}" "-DCMAKE_PREFIX_PATH=${prefix}")
run_step("build template" ${CMAKE_COMMAND} --build "${plugin_build}")
if(NOT EXISTS "${plugin_build}/libubersim_template_drive.so")
  message(FATAL_ERROR "the template build produced no libubersim_template_drive.so")
endif()

# 3. The installed ubersim finds and accepts it through UBERSIM_PLUGIN_PATH.
set(ubersim "${prefix}/bin/ubersim")
run_step("ubersim plugins" ${CMAKE_COMMAND} -E env "UBERSIM_PLUGIN_PATH=${plugin_build}"
         "${ubersim}" plugins)
if(NOT STEP_OUTPUT MATCHES "template_drive +drive +1\\.0\\.0 +0\\.1")
  message(FATAL_ERROR "ubersim plugins does not list template_drive:\n${STEP_OUTPUT}")
endif()

# 4. A world with two robots driven by it loads (its parameters checked against the plugin's
#    schema) and runs; the world names the plugin folder itself (plugin_paths).
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
run_step("ubersim run" "${ubersim}" run "${WORK_DIR}/world.yaml" --fast --duration 2 --quiet)
if(NOT STEP_OUTPUT MATCHES "2 robots" OR NOT STEP_OUTPUT MATCHES "stopped at sim time 2")
  message(FATAL_ERROR "the world with template_drive robots did not run:\n${STEP_OUTPUT}")
endif()

# 5. A typo in the plugin's block is reported with file, line, column and key.
file(WRITE "${WORK_DIR}/typo-robot.yaml" "kind: robot\nname: typo-bot\n"
  "body: {mass: 2.3, radius: 0.09, height: 0.15}\n"
  "drive:\n  plugin: template_drive\n  max_sped: 3.0\n")
execute_process(COMMAND ${CMAKE_COMMAND} -E env "UBERSIM_PLUGIN_PATH=${plugin_build}"
                "${ubersim}" validate "${WORK_DIR}/typo-robot.yaml"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 3 OR NOT out MATCHES "typo-robot.yaml:6:3: .*max_sped")
  message(FATAL_ERROR "the typo was not reported as file:6:3 with the key (exit ${rc}):\n${out}${err}")
endif()
message(STATUS "template plugin: installed, built out of tree, listed, run and validated")
