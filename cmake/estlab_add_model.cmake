# estlab_add_model(TARGET FILE [TUNER]): builds the model in FILE (a .model
# file or a C++ model header, docs/models.md) into the program that links
# TARGET.
#
#   find_package(estlab REQUIRED)
#   estlab_add_model(pendulum_model pendulum.model)          # filters and simulator
#   estlab_add_model(spring_model include/spring.h TUNER)    # ... and the Q/R tuner
#   add_executable(app main.cpp)
#   target_link_libraries(app PRIVATE pendulum_model spring_model estlab::estlab)
#
#   // main.cpp: the model registered itself under its name
#   const estlab::ModelEntry& m = estlab::FindModel("pendulum-file");
#   // its type, for the filter templates: #include "pendulum_model/model.h"
#
# At build time (and again whenever FILE changes) it runs
# `estlab model source FILE --out <binary dir>/estlab_models/TARGET [--tuner]`,
# which writes model.h, entry.cpp (and tune.cpp): the same header and entry
# code that estlab compiles for a model file at run time
# (src/registry/model_source.h), so a model behaves the same linked or loaded.
# TARGET is an OBJECT library linking estlab::estlab; its include folder
# makes "TARGET/model.h" includable by whoever links it.
#
# WARNING: TARGET must be an object library (it is): its entry registers the
# model from a static initialiser, which a static library's linker would drop.
# Model names must be unique in a program (FindModel throws for a name given
# twice, built-in names included). Compiling entry.cpp takes about a minute
# (every filter is instantiated for the model); TUNER about two more.
#
# What it runs and links is set by whoever includes this file: the installed
# package (estlabConfig.cmake) or estlab's own tree (the benchmarks):
#   ESTLAB_COMMAND          the estlab command to run
#   ESTLAB_COMMAND_DEPENDS  what the generation depends on (the binary or its target)
#   ESTLAB_MODEL_LINK       the library target (estlab::estlab or estlab_lib)
function(estlab_add_model target file)
  cmake_parse_arguments(PARSE_ARGV 2 arg "TUNER" "" "")
  if(arg_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "estlab_add_model(${target} ${file}): unknown arguments "
                        "'${arg_UNPARSED_ARGUMENTS}' (usage: estlab_add_model(TARGET FILE [TUNER]))")
  endif()
  get_filename_component(file ${file} ABSOLUTE BASE_DIR ${CMAKE_CURRENT_SOURCE_DIR})
  if(NOT EXISTS ${file})
    message(FATAL_ERROR "estlab_add_model(${target}): model file '${file}' not found")
  endif()
  set(root ${CMAKE_CURRENT_BINARY_DIR}/estlab_models)
  set(dir ${root}/${target})
  set(sources ${dir}/entry.cpp)
  set(tuner_flag "")
  if(arg_TUNER)
    list(APPEND sources ${dir}/tune.cpp)
    set(tuner_flag --tuner)
  endif()
  add_custom_command(OUTPUT ${dir}/model.h ${sources}
    COMMAND ${ESTLAB_COMMAND} model source ${file} --out ${dir} ${tuner_flag}
    DEPENDS ${file} ${ESTLAB_COMMAND_DEPENDS}
    COMMENT "estlab model source ${file}"
    VERBATIM)
  add_library(${target} OBJECT ${sources})
  target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${root}>)
  target_link_libraries(${target} PUBLIC ${ESTLAB_MODEL_LINK})
endfunction()
