# The ctest `install_example` (label install; tests/CMakeLists.txt): stages
# `cmake --install` of the build into <build>/install-test/prefix, then
# configures, builds (with -Werror) and runs examples/ekf_user_model against
# it, as a user of the installed package would; last, checks that the
# installed estlab compiles run-time models against the installed headers.
#
#   cmake -DESTLAB_SOURCE_DIR=. -DESTLAB_BUILD_DIR=build -P tests/install/example_test.cmake
#
# Fails (cmake exits non-zero) at the first step that fails, naming it.
foreach(var ESTLAB_SOURCE_DIR ESTLAB_BUILD_DIR)
  if(NOT ${var})
    message(FATAL_ERROR "give -D${var}=...")
  endif()
  get_filename_component(${var} ${${var}} ABSOLUTE)
endforeach()
set(work ${ESTLAB_BUILD_DIR}/install-test)
set(prefix ${work}/prefix)
file(REMOVE_RECURSE ${work})

function(step what)
  string(TIMESTAMP start "%s")
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE status)
  string(TIMESTAMP end "%s")
  math(EXPR seconds "${end} - ${start}")
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "install test: ${what} failed (${status}): ${ARGN}")
  endif()
  message(STATUS "install test: ${what}: ok (${seconds} s)")
endfunction()

step("install" ${CMAKE_COMMAND} --install ${ESTLAB_BUILD_DIR} --prefix ${prefix})

find_program(ccache ccache)
set(launcher "")
if(ccache)
  set(launcher -DCMAKE_CXX_COMPILER_LAUNCHER=${ccache})
endif()
step("configure the example" ${CMAKE_COMMAND} -S ${ESTLAB_SOURCE_DIR}/examples/ekf_user_model
  -B ${work}/example -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release
  "-DCMAKE_CXX_FLAGS=-Wall -Wextra -Werror" ${launcher})
step("build the example" ${CMAKE_COMMAND} --build ${work}/example -j2)
step("run the example" ${work}/example/ekf_user_model)

# The installed estlab compiles a model file against <prefix>/include/estlab
# (src/registry/model_plugin.cpp), not the source tree: a probe header found
# only there is included, and the next include stops the compile at once.
file(WRITE ${prefix}/include/estlab/estlab_install_probe.h "// install test probe\n")
file(WRITE ${work}/probe/probe.h
  "#include \"estlab_install_probe.h\"\n#include \"estlab_install_probe_stop.h\"\n")
execute_process(COMMAND ${prefix}/bin/estlab --model-cache ${work}/probe/cache
  model build ${work}/probe/probe.h RESULT_VARIABLE status ERROR_VARIABLE err OUTPUT_QUIET)
if(NOT status EQUAL 2 OR NOT err MATCHES "estlab_install_probe_stop\\.h")
  message(FATAL_ERROR "install test: the installed estlab does not compile models against "
                      "the installed headers (exit ${status}):\n${err}")
endif()
message(STATUS "install test: installed estlab compiles models against ${prefix}/include/estlab: ok")

# The Python module, installed (issue 36): PREFIX/lib/python3/dist-packages
# on PYTHONPATH, as docs/python.md says; it is the installed one that loads,
# it filters, and it too compiles model files against the installed headers.
if(ESTLAB_PYTHON)
  set(site ${prefix}/lib/python3/dist-packages)
  file(WRITE ${work}/python_probe.py "
import os, sys, estlab
assert estlab.__file__.startswith(sys.argv[1]), estlab.__file__
t = [0.0125 * k for k in range(40)]
run = estlab.filter('pendulum', {'t': t, 'z_sin_theta': [0.5] * 40}, measure='sin', r_diag=0.1,
                    q_diag=[1e-4, 1e-4])
assert run.x.shape == (40, 2), run.x.shape
try:
    estlab.Model(sys.argv[2])
except estlab.InputError as e:
    assert 'estlab_install_probe_stop.h' in str(e), str(e)
    print('python probe: ok')
")
  execute_process(COMMAND ${CMAKE_COMMAND} -E env PYTHONPATH=${site}
    ESTLAB_MODEL_CACHE=${work}/probe/pycache PYTHONDONTWRITEBYTECODE=1
    ${Python3_EXECUTABLE} ${work}/python_probe.py ${site} ${work}/probe/probe.h
    RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT status EQUAL 0 OR NOT out MATCHES "python probe: ok")
    message(FATAL_ERROR "install test: the installed Python module (${status}):\n${out}\n${err}")
  endif()
  message(STATUS "install test: the installed Python module filters and compiles models "
                 "against ${prefix}/include/estlab: ok")
endif()
