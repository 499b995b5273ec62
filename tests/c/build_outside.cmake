# ctest fixture: configures and builds tests/c/outside against the installed occseg only
# (CMAKE_PREFIX_PATH = the test prefix).  -DSRC=... -DBIN=... -DPREFIX=... -DCC=... -DCXX=...
# -DFLAGS=...: the sanitizer flags of a sanitizer build (a sanitized library needs sanitized
# programs: the runtime must come first), empty otherwise; -DLDFLAGS=...: the same for linking
# the programs (FLAGS when not given).
if(NOT DEFINED LDFLAGS)
  set(LDFLAGS "${FLAGS}")
endif()
file(REMOVE_RECURSE ${BIN})
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SRC} -B ${BIN} -DCMAKE_PREFIX_PATH=${PREFIX}
                        -DCMAKE_C_COMPILER=${CC} -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_BUILD_TYPE=Debug
                        "-DCMAKE_C_FLAGS=${FLAGS}" "-DOCCSEG_SANITIZE_FLAGS=${FLAGS}" "-DCMAKE_CXX_FLAGS=${FLAGS}" "-DCMAKE_EXE_LINKER_FLAGS=${LDFLAGS}"
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configuring the outside project failed (${rc})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${BIN} -j2 RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "building the outside project failed (${rc})")
endif()
