# ctest fixture: installs the whole build into a fresh temporary prefix, as a user would, and
# checks that every file a C user needs is there.  -DBUILD=... -DPREFIX=... -DLIBDIR=...
file(REMOVE_RECURSE ${PREFIX})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD} --prefix ${PREFIX} RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install ${BUILD} --prefix ${PREFIX} failed (${rc})")
endif()
foreach(f include/occseg/occseg.h include/occseg/occseg_version.h
          ${LIBDIR}/liboccseg.so ${LIBDIR}/liboccseg.so.0 ${LIBDIR}/pkgconfig/occseg.pc
          ${LIBDIR}/cmake/occseg/occsegConfig.cmake ${LIBDIR}/cmake/occseg/occsegConfigVersion.cmake
          ${LIBDIR}/cmake/occseg/occsegTargets.cmake
          share/doc/occseg/README.md share/doc/occseg/docs/cli.md share/doc/occseg/docs/c-api.md)
  if(NOT EXISTS ${PREFIX}/${f})
    message(FATAL_ERROR "installed tree lacks ${f}")
  endif()
endforeach()
file(READ ${PREFIX}/${LIBDIR}/pkgconfig/occseg.pc pc)
if(NOT pc MATCHES "prefix=${PREFIX}\n")
  message(FATAL_ERROR "occseg.pc does not record the install prefix ${PREFIX}:\n${pc}")
endif()
