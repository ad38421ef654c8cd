# The layering of estlab, checked on every configure (and by the ctest
# `layers`): a file may include headers of its own folder and of folders in
# LOWER layers only. An upward include fails the configure with the file, the
# line and the two layers named.
#
#   0 core       src/core         types, parsing, white-accel Q
#   1 io         src/io           CSV, JSON, output files
#   1 modelfile  src/modelfile    the .model language: parse, check, generate C++
#   2 models     models           the model contract (model.h) and the models
#   3 ode        src/ode          transitions: fixed-step, CVODES, AD
#   4 filters    src/filters      the filter steps and classes, noise adapters
#   5 run, sim   src/run src/sim  one filter run / one simulation
#   6 adaptive   adaptive         the likelihood and the Q/R tuner
#   7 registry   src/registry     the model list and per-model entry points
#   8 options    src/options      the filter key table, FilterSettings -> FilterSpec
#   9 config     studies/config   the study file parser (StudyConfig)
#  10 results    studies/results  the results folder: columns, row files,
#                                 study.state, checksums, run coverage
#  11 report     studies/report   report.md, summary statistics, figures
#  12 study run  studies/run      running a study: runner, tuning, task order,
#                                 Slurm, merge of shards, output error
#  13 cli        src/cli          the estlab command
#  14 python     src/python       the Python module (import estlab)
#
# Run by hand: cmake -DESTLAB_SOURCE_DIR=. -P cmake/check_layers.cmake
set(ESTLAB_LAYERS
  "src/core=0" "src/io=1" "src/modelfile=1" "models=2" "src/ode=3" "src/filters=4" "src/run=5" "src/sim=5"
  "adaptive=6" "src/registry=7" "src/options=8" "studies/config=9" "studies/results=10"
  "studies/report=11" "studies/run=12" "src/cli=13" "src/python=14")

function(estlab_layer_of path out_rank out_folder)
  set(rank -1)
  set(folder "")
  foreach(entry ${ESTLAB_LAYERS})
    string(REPLACE "=" ";" kv "${entry}")
    list(GET kv 0 dir)
    list(GET kv 1 r)
    string(LENGTH "${dir}/" len)
    string(SUBSTRING "${path}" 0 ${len} head)
    if(head STREQUAL "${dir}/")
      set(rank ${r})
      set(folder ${dir})
    endif()
  endforeach()
  set(${out_rank} ${rank} PARENT_SCOPE)
  set(${out_folder} ${folder} PARENT_SCOPE)
endfunction()

if(NOT ESTLAB_SOURCE_DIR)
  set(ESTLAB_SOURCE_DIR ${CMAKE_SOURCE_DIR})
endif()
# Absolute: with a relative folder (-DESTLAB_SOURCE_DIR=.) the globs below
# find nothing and the check would pass without looking.
get_filename_component(ESTLAB_SOURCE_DIR "${ESTLAB_SOURCE_DIR}" ABSOLUTE)
file(GLOB_RECURSE sources RELATIVE ${ESTLAB_SOURCE_DIR}
  ${ESTLAB_SOURCE_DIR}/src/*.h ${ESTLAB_SOURCE_DIR}/src/*.cpp
  ${ESTLAB_SOURCE_DIR}/models/*.h ${ESTLAB_SOURCE_DIR}/adaptive/*.h
  ${ESTLAB_SOURCE_DIR}/adaptive/*.cpp ${ESTLAB_SOURCE_DIR}/studies/*.h
  ${ESTLAB_SOURCE_DIR}/studies/*.cpp)
set(violations "")
foreach(file ${sources})
  estlab_layer_of("${file}" from_rank from_folder)
  if(from_rank LESS 0)
    list(APPEND violations "${file}: not in any layer (add its folder to cmake/check_layers.cmake)")
    continue()
  endif()
  file(STRINGS ${ESTLAB_SOURCE_DIR}/${file} lines REGEX "^#include \"[^\"]+/[^\"]+\"")
  foreach(line ${lines})
    string(REGEX REPLACE "^#include \"([^\"]+)\".*" "\\1" header "${line}")
    estlab_layer_of("${header}" to_rank to_folder)
    if(to_rank LESS 0)
      continue()
    endif()
    if(NOT to_folder STREQUAL from_folder AND NOT to_rank LESS from_rank)
      list(APPEND violations
        "${file} (${from_folder}, layer ${from_rank}) includes ${header} (${to_folder}, layer ${to_rank})")
    endif()
  endforeach()
endforeach()
if(violations)
  list(JOIN violations "\n  " text)
  message(FATAL_ERROR "estlab: layering violated (a lower layer includes a higher one):\n  ${text}")
endif()
