# `occseg segment` with a plugin's reader, stages and parameter: -DOCCSEG=... -DWORK=... -DPLUGIN_DIR=...
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
# A 16^3 .occtxt map (read by the example plugin): free 0.1, an occupied cube 0.9 at [4, 12)^3.
set(values "")
foreach(z RANGE 15)
  foreach(y RANGE 15)
    foreach(x RANGE 15)
      if(x GREATER_EQUAL 4 AND x LESS 12 AND y GREATER_EQUAL 4 AND y LESS 12 AND z GREATER_EQUAL 4 AND z LESS 12)
        string(APPEND values "0.9\n")
      else()
        string(APPEND values "0.1\n")
      endif()
    endforeach()
  endforeach()
endforeach()
file(WRITE ${WORK}/cube.occtxt "occtxt 16 16 16 0.05 0 0 0\n${values}")

function(run expect_rc expect_text)
  execute_process(COMMAND ${CMAKE_COMMAND} -E env OCCSEG_PLUGIN_PATH=${PLUGIN_DIR} ${ARGN}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL expect_rc OR NOT "${out}${err}" MATCHES "${expect_text}")
    message(FATAL_ERROR "${ARGN}\nexit ${rc} (expected ${expect_rc}), output:\n${out}${err}\n(expected to match: ${expect_text})")
  endif()
endfunction()

run(0 "" ${OCCSEG} segment ${WORK}/cube.occtxt --out ${WORK}/out --param texture=lbp6ri --param similarity=l1
    --param ri_flat_below=0.05 --param smax=8 --param smin=2)
file(READ ${WORK}/out/segments.json json)
string(JSON n LENGTH "${json}" segments)
if(NOT n EQUAL 2)
  message(FATAL_ERROR "expected 2 segments (free around, occupied cube), got ${n}:\n${json}")
endif()
foreach(i 0 1)
  string(JSON state GET "${json}" segments ${i} state)
  string(JSON voxels GET "${json}" segments ${i} voxels)
  if(state STREQUAL "occupied" AND NOT voxels EQUAL 512)
    message(FATAL_ERROR "the occupied segment has ${voxels} voxels, not 8^3 = 512")
  endif()
endforeach()
# Unknown names stay errors (exit 1, usage), with or without the plugin.
run(1 "parameter 'ri_flat_belw': no such parameter" ${OCCSEG} segment ${WORK}/cube.occtxt --out ${WORK}/bad
    --param ri_flat_belw=0.1)
run(1 "'nope' is not a registered texture operator \\(registered: lbp6, lbp8, lbp6ri\\)" ${OCCSEG} segment
    ${WORK}/cube.occtxt --out ${WORK}/bad --param texture=nope)
