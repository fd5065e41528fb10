# ctest driver: install the build tree into a scratch prefix, then configure, build and run the
# consumer against it; then the same for samples/engine_example, which streams a tree baked by
# the installed `octolod` from the bundled sample for a few frames (so the example cannot rot).
# Variables: BUILD_DIR, SOURCE_DIR, SCRATCH, ENGINE_EXAMPLE_DIR, SAMPLE_PLY.
file(REMOVE_RECURSE ${SCRATCH})

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(output "${out}" PARENT_SCOPE)
endfunction()

run("install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${SCRATCH}/prefix)

# the tiny consumer
run("consumer configure" ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${SCRATCH}/build
    -DCMAKE_PREFIX_PATH=${SCRATCH}/prefix -DCMAKE_BUILD_TYPE=Release)
run("consumer build" ${CMAKE_COMMAND} --build ${SCRATCH}/build)
run("consumer run" ${SCRATCH}/build/consumer)

# the engine example on a freshly baked tree
run("bake for the engine example" ${SCRATCH}/prefix/bin/octolod bake ${SAMPLE_PLY} -o ${SCRATCH}/rock --memory 64M)
run("engine example configure" ${CMAKE_COMMAND} -S ${ENGINE_EXAMPLE_DIR} -B ${SCRATCH}/engine_example
    -DCMAKE_PREFIX_PATH=${SCRATCH}/prefix -DCMAKE_BUILD_TYPE=Release)
run("engine example build" ${CMAKE_COMMAND} --build ${SCRATCH}/engine_example)
run("engine example run" ${SCRATCH}/engine_example/engine_example ${SCRATCH}/rock 20 16)
if(NOT output MATCHES "frame  19: ")
  message(FATAL_ERROR "engine example printed no line for its last frame:\n${output}")
endif()
