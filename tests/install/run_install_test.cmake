# The install test: cmake --install of the (already built) project into a temporary prefix, then the user
# project beside this file configured and built against it (find_package), its test run, and a
# program built with the flags of pkg-config alone.
# cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... -DCXX=<compiler> -P run_install_test.cmake
foreach(v BUILD_DIR SOURCE_DIR WORK_DIR CXX)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "run_install_test.cmake needs -D${v}=...")
  endif()
endforeach()

function(run)
  execute_process(COMMAND ${ARGV} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGV}\n${out}")
  endif()
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
foreach(f include/vecat/testing/virtual_segment.hpp include/vecat/cia402/drive.hpp include/vecat/esi/esi_writer.hpp
          bin/vecat)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
file(GLOB pc ${prefix}/lib*/pkgconfig/vecat.pc ${prefix}/lib/*/pkgconfig/vecat.pc)
if(NOT pc)
  message(FATAL_ERROR "no vecat.pc installed")
endif()

# The user's project sees only the prefix (not the build tree).
run(${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/install -B ${WORK_DIR}/user -G Ninja -DCMAKE_BUILD_TYPE=Release
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER} "-DCMAKE_CXX_FLAGS=${USER_FLAGS}")
run(${CMAKE_COMMAND} --build ${WORK_DIR}/user -j2)
run(${WORK_DIR}/user/user_test)
# The same through pkg-config (vecat.pc) with the plain compiler.
find_program(PKG_CONFIG pkg-config REQUIRED)
get_filename_component(pcdir ${pc} DIRECTORY)
execute_process(COMMAND ${CMAKE_COMMAND} -E env PKG_CONFIG_PATH=${pcdir} ${PKG_CONFIG} --cflags --libs vecat
                RESULT_VARIABLE rc OUTPUT_VARIABLE flags OUTPUT_STRIP_TRAILING_WHITESPACE)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "pkg-config --cflags --libs vecat failed")
endif()
separate_arguments(flags UNIX_COMMAND "${flags} ${USER_FLAGS}")
run(${CXX} ${SOURCE_DIR}/tests/install/pkgconfig_user.cpp ${flags} -o ${WORK_DIR}/pkgconfig_user)
run(${WORK_DIR}/pkgconfig_user)

message(STATUS "install test: find_package(vecat) from ${prefix} and vecat::testing work")
file(REMOVE_RECURSE ${WORK_DIR})
