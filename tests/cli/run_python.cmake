# Runs a Python check script with Debian's interpreter (which has numpy), passing the tool path,
# a fresh work directory and the shared data directory.
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
execute_process(COMMAND ${PYTHON} ${SCRIPT} ${OCCSEG} ${WORK} ${DATA} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${SCRIPT} failed (${rc})")
endif()
