# `cmake --install build --prefix PREFIX` (`make install PREFIX=...`):
#
#   PREFIX/bin/estlab                         the command
#   PREFIX/lib/libestlab_*.a                  the layer libraries
#   PREFIX/include/estlab/{src,models,adaptive,studies}/**.h, estlab_version.h
#                                             the headers, included as in the tree
#                                             ("src/registry/registry.h")
#   PREFIX/lib/cmake/estlab/                  the CMake package: estlabConfig.cmake,
#                                             its version file, estlabTargets.cmake,
#                                             estlab_add_model.cmake
#
# A project then writes
#   find_package(estlab REQUIRED)       # estlab::estlab, estlab_add_model(), ESTLAB_EXECUTABLE
#   estlab_add_model(my_model my.model) # docs/models.md
#   target_link_libraries(my_program PRIVATE my_model estlab::estlab)
# and the installed estlab compiles run-time models against the installed
# headers (src/registry/model_plugin.cpp finds them relative to the binary).
#
# Included from the top-level CMakeLists.txt after the layer targets.
include(CMakePackageConfigHelpers)

set(ESTLAB_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/estlab)
set(ESTLAB_LAYER_TARGETS estlab_core estlab_modelfile estlab_models estlab_ode estlab_filters
  estlab_run estlab_adaptive estlab_registry estlab_options estlab_studies estlab_cli)

# estlab::estlab is estlab_lib (INTERFACE: every layer, in link order).
set_target_properties(estlab_lib PROPERTIES EXPORT_NAME estlab)
install(TARGETS estlab RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS ${ESTLAB_LAYER_TARGETS} estlab_lib EXPORT estlabTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${ESTLAB_INSTALL_INCLUDEDIR})
install(EXPORT estlabTargets NAMESPACE estlab:: DESTINATION ${ESTLAB_INSTALL_CMAKEDIR})

foreach(folder src models adaptive studies)
  install(DIRECTORY ${CMAKE_SOURCE_DIR}/${folder}/ DESTINATION ${ESTLAB_INSTALL_INCLUDEDIR}/${folder}
    FILES_MATCHING PATTERN "*.h")
endforeach()
install(FILES ${CMAKE_BINARY_DIR}/generated/estlab_version.h
  DESTINATION ${ESTLAB_INSTALL_INCLUDEDIR})

configure_package_config_file(${CMAKE_SOURCE_DIR}/cmake/estlabConfig.cmake.in
  ${CMAKE_BINARY_DIR}/estlabConfig.cmake
  INSTALL_DESTINATION ${ESTLAB_INSTALL_CMAKEDIR}
  PATH_VARS CMAKE_INSTALL_BINDIR)
write_basic_package_version_file(${CMAKE_BINARY_DIR}/estlabConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/estlabConfig.cmake ${CMAKE_BINARY_DIR}/estlabConfigVersion.cmake
  ${CMAKE_SOURCE_DIR}/cmake/estlab_add_model.cmake
  DESTINATION ${ESTLAB_INSTALL_CMAKEDIR})
