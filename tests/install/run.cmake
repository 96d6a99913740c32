# The downstream test (ctest install_tree, tests/CMakeLists.txt): installs the build tree into a
# fresh prefix (cmake --install), configures and builds tests/install (find_package(subvec)) against
# it alone, and runs the program on examples/01-disk.svec.json. Any failing step fails the test with
# its output. With PYTHON and PYTHON_DIR (the module's directory under the prefix), the installed
# Python module is imported from there too. Arguments (-D): BUILD_DIR, SOURCE_DIR, WORK_DIR,
# GENERATOR, CXX [, PYTHON, PYTHON_DIR].
cmake_minimum_required(VERSION 3.25)
foreach(var BUILD_DIR SOURCE_DIR WORK_DIR GENERATOR CXX)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run.cmake: -D${var}=... is missing")
  endif()
endforeach()

set(prefix ${WORK_DIR}/prefix)
set(build ${WORK_DIR}/build)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})

function(step name)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "install_tree: ${name} failed (${rc}):\n${out}")
  endif()
  message(STATUS "install_tree: ${name}: ok")
  set(step_output "${out}" PARENT_SCOPE)
endfunction()

step("cmake --install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
foreach(f bin/subvec include/subvec/render/renderer.h lib/cmake/subvec/subvecConfig.cmake)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "install_tree: ${f} is not installed")
  endif()
endforeach()
step("bin/subvec --version" ${prefix}/bin/subvec --version)
# Only the prefix: no path into the source or build tree may be needed.
step("configure tests/install" ${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/install -B ${build}
     -G ${GENERATOR} -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=${CXX}
     -DCMAKE_PREFIX_PATH=${prefix})
step("build tests/install" ${CMAKE_COMMAND} --build ${build})
step("run the downstream program" ${build}/downstream ${SOURCE_DIR}/examples/01-disk.svec.json
     ${WORK_DIR}/disk@2x.png)
message(STATUS "${step_output}")
if(NOT EXISTS ${WORK_DIR}/disk@2x.png)
  message(FATAL_ERROR "install_tree: the downstream program wrote no PNG")
endif()

if(DEFINED PYTHON AND DEFINED PYTHON_DIR)
  step("import the installed Python module" ${PYTHON} ${SOURCE_DIR}/tests/install/check_module.py
       ${prefix}/${PYTHON_DIR} ${SOURCE_DIR}/examples/01-disk.svec.json)
  message(STATUS "${step_output}")
endif()
