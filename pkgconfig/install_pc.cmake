# occseg_install_pc(TEMPLATE NAME): installs <libdir>/pkgconfig/NAME.pc made from TEMPLATE (one of
# the *.pc.in beside this file), for occseg.pc (capi/) and occseg-pcl.pc / occseg-octomap.pc
# (adapters/). TEMPLATE is configured now with the caller's variables, @OCCSEG_PC_LIBDIR@ and
# @OCCSEG_PC_INCLUDEDIR@ (relative to ${prefix} unless absolute); @OCCSEG_PC_PREFIX@ is filled at
# install time, so that `cmake --install --prefix P` records P.
function(occseg_install_pc template name)
  foreach(dir LIBDIR INCLUDEDIR)
    if(IS_ABSOLUTE "${CMAKE_INSTALL_${dir}}")
      set(OCCSEG_PC_${dir} "${CMAKE_INSTALL_${dir}}")
    else()
      set(OCCSEG_PC_${dir} "\${prefix}/${CMAKE_INSTALL_${dir}}")
    endif()
  endforeach()
  set(OCCSEG_PC_PREFIX "@OCCSEG_PC_PREFIX@")  # kept for the install-time pass below
  configure_file(${template} ${CMAKE_CURRENT_BINARY_DIR}/${name}.pc.in @ONLY)
  # Staged per destination: concurrent installs into different prefixes (ctest runs several)
  # must not install each other's file.
  install(CODE "
    set(OCCSEG_PC_PREFIX \"\${CMAKE_INSTALL_PREFIX}\")
    string(MD5 stage \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}\")
    configure_file(\"${CMAKE_CURRENT_BINARY_DIR}/${name}.pc.in\" \"${CMAKE_CURRENT_BINARY_DIR}/pc/\${stage}/${name}.pc\" @ONLY)
    file(INSTALL DESTINATION \"\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_LIBDIR}/pkgconfig\" TYPE FILE
         FILES \"${CMAKE_CURRENT_BINARY_DIR}/pc/\${stage}/${name}.pc\")")
endfunction()
