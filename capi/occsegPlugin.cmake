# occseg_add_plugin(<target> SOURCES <file>... [INSTALL])
#
# Builds an occseg plugin: a MODULE library (no "lib" prefix) compiled against occseg_plugin.h
# and NOT linked with liboccseg (the host hands a plugin everything it may call), with hidden
# symbols except the entry point (OCCSEG_PLUGIN_EXPORT) and --no-undefined so that a missing
# function shows at link time, not when the plugin is loaded. INSTALL installs it into
# OCCSEG_PLUGIN_DIR, the folder occseg_plugins_load_default() searches (<libdir>/occseg/plugins
# of the install prefix). Included by occsegConfig.cmake (find_package(occseg)); the occseg
# build uses it too for its own reader plugins.
include_guard(GLOBAL)
include(GNUInstallDirs)

if(NOT DEFINED OCCSEG_PLUGIN_DIR)
  set(OCCSEG_PLUGIN_DIR ${CMAKE_INSTALL_LIBDIR}/occseg/plugins)
endif()

function(occseg_add_plugin target)
  cmake_parse_arguments(ARG "INSTALL" "" "SOURCES" ${ARGN})
  if(NOT ARG_SOURCES)
    message(FATAL_ERROR "occseg_add_plugin(${target}): SOURCES is required")
  endif()
  add_library(${target} MODULE ${ARG_SOURCES})
  # The headers of occseg::occseg, but not its library.
  target_include_directories(${target} PRIVATE $<TARGET_PROPERTY:occseg::occseg,INTERFACE_INCLUDE_DIRECTORIES>)
  set_target_properties(${target} PROPERTIES PREFIX "" C_VISIBILITY_PRESET hidden CXX_VISIBILITY_PRESET hidden
                                             VISIBILITY_INLINES_HIDDEN ON)
  # Sanitizer runtimes are only linked into programs (clang): a build against a sanitized occseg
  # sets OCCSEG_SANITIZE_FLAGS (the occseg build's own variable; tests/c/build_outside.cmake).
  if(NOT OCCSEG_SANITIZE_FLAGS)
    target_link_options(${target} PRIVATE -Wl,--no-undefined)
  endif()
  if(ARG_INSTALL)
    install(TARGETS ${target} LIBRARY DESTINATION ${OCCSEG_PLUGIN_DIR})
  endif()
endfunction()
