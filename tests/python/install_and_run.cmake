# ctest: installs the build into a fresh prefix, then runs installed_smoke.py from that prefix
# with a clean environment (no OCCSEG_LIBRARY, no source tree on PYTHONPATH), then again after
# moving the prefix elsewhere (the package must find the library relative to itself) and with
# OCCSEG_LIBRARY pointing at another copy (the install location comes first).
# -DBUILD=... -DWORK=... -DLIBDIR=... -DPYTHON=... -DSCRIPT=... -DOTHER_LIBRARY=... [-DDATA=shared data]
file(REMOVE_RECURSE ${WORK})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD} --prefix ${WORK}/prefix RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install ${BUILD} --prefix ${WORK}/prefix failed (${rc})")
endif()
foreach(f lib/python3/dist-packages/occseg/__init__.py lib/python3/dist-packages/occseg/_config.py)
  if(NOT EXISTS ${WORK}/prefix/${f})
    message(FATAL_ERROR "installed tree lacks ${f}")
  endif()
endforeach()
file(GLOB stray ${WORK}/prefix/lib/python3/dist-packages/occseg/*.in ${WORK}/prefix/lib/python3/dist-packages/occseg/__pycache__)
if(stray)
  message(FATAL_ERROR "installed package holds stray files: ${stray}")
endif()

function(smoke prefix)
  execute_process(COMMAND ${CMAKE_COMMAND} -E env --unset=OCCSEG_LIBRARY --unset=LD_LIBRARY_PATH
      --unset=OCCSEG_PLUGIN_PATH --unset=OCCSEG_NO_DEFAULT_PLUGINS OCCSEG_SHARED_DATA=${DATA}
      PYTHONPATH=${prefix}/lib/python3/dist-packages PYTHONDONTWRITEBYTECODE=1 ${ARGN}
      ${PYTHON} ${SCRIPT} ${prefix} ${prefix}/${LIBDIR}
    WORKING_DIRECTORY ${WORK} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "installed package in ${prefix} failed (${rc})")
  endif()
endfunction()

smoke(${WORK}/prefix)
file(RENAME ${WORK}/prefix ${WORK}/moved)
smoke(${WORK}/moved)
smoke(${WORK}/moved OCCSEG_LIBRARY=${OTHER_LIBRARY})
