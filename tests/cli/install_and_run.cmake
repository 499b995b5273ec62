# ctest: installs the build into a fresh prefix and runs check_installed.py on <prefix>/bin/occseg
# with a clean environment (no LD_LIBRARY_PATH), then again after moving the prefix elsewhere:
# the tool must find liboccseg_pcl / liboccseg_octomap through its RPATH ($ORIGIN/../<libdir>).
# -DBUILD=... -DWORK=... -DLIBDIR=... -DPYTHON=... -DSCRIPT=... -DDATA=...
file(REMOVE_RECURSE ${WORK})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD} --prefix ${WORK}/prefix RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install ${BUILD} --prefix ${WORK}/prefix failed (${rc})")
endif()
foreach(prefix prefix moved)
  if(prefix STREQUAL "moved")
    file(RENAME ${WORK}/prefix ${WORK}/moved)
  endif()
  execute_process(COMMAND ${CMAKE_COMMAND} -E env --unset=LD_LIBRARY_PATH --unset=OCCSEG_PLUGIN_PATH
      ${PYTHON} ${SCRIPT} ${WORK}/${prefix} ${LIBDIR} ${DATA}
    WORKING_DIRECTORY ${WORK} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "the installed occseg in ${WORK}/${prefix} failed (${rc})")
  endif()
endforeach()
