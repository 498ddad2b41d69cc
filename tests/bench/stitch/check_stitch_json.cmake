# Runs `microdex-bench stitch --quick --json OUT` and checks the report: two compliance levels
# within 5 % of the Navier series off the load; the rigid run and the one at the scene's
# relaxation time both tie the surgeon's knot, the latter with the bite lifted and the rods'
# loads tracked and balanced against the hands' pull, and so does the stitch with the in-plane
# key turned the other way at its own jig; the in-plane compliance's error against the annulus;
# the slip knot's recipe.
execute_process(COMMAND ${BENCH} stitch --quick --json ${OUT} RESULT_VARIABLE rc
                OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "microdex-bench stitch exited with ${rc}: ${err}")
endif()
file(READ ${OUT} json)
string(JSON n LENGTH "${json}" compliance)
if(NOT n EQUAL 2)
  message(FATAL_ERROR "expected 2 compliance levels, got ${n}")
endif()
foreach(i 0 1)
  string(JSON e GET "${json}" compliance ${i} off_diagonal_error)
  if(e GREATER 0.05)
    message(FATAL_ERROR "compliance[${i}].off_diagonal_error ${e} > 0.05")
  endif()
  string(JSON ms GET "${json}" compliance ${i} build_ms)
  if(NOT ms GREATER 0)
    message(FATAL_ERROR "compliance[${i}].build_ms ${ms}")
  endif()
endforeach()
string(JSON n LENGTH "${json}" coupling)
if(NOT n EQUAL 4)
  message(FATAL_ERROR "expected 4 coupling runs (rigid, the scene's, the in-plane key the other "
                      "way, the slip knot's recipe), got ${n}")
endif()
foreach(i 0 1 2)
  string(JSON knot GET "${json}" coupling ${i} knot)
  if(NOT knot STREQUAL "surgeons")
    message(FATAL_ERROR "coupling[${i}] tied '${knot}', not a surgeon's knot")
  endif()
endforeach()
# The relaxed runs, without and with the in-plane compliance: run to the end, the bite lifted,
# the rods' loads tracked and balanced against the hands' pull along the normal.
foreach(i 1 2 3)
  string(JSON refused GET "${json}" coupling ${i} refused)
  string(JSON bite GET "${json}" coupling ${i} bite_um)
  string(JSON trailing GET "${json}" coupling ${i} trailing)
  string(JSON balance GET "${json}" coupling ${i} balance)
  if(refused OR NOT bite GREATER 10 OR trailing GREATER 0.05 OR balance GREATER 0.1)
    message(FATAL_ERROR "coupling[${i}]: refused ${refused}, bite ${bite} um, trailing "
                        "${trailing}, balance ${balance}")
  endif()
endforeach()
string(JSON a GET "${json}" coupling 1 in_plane)
string(JSON b GET "${json}" coupling 2 in_plane)
if(a STREQUAL b)
  message(FATAL_ERROR "coupling[2] should turn the scene's in-plane key the other way")
endif()
# The in-plane stitch at the normal-only stitch's jig (4.3 mm): the knot capsizes onto one
# strand, a slip knot, the knot-topology scene's assets/knots/tied_slip.obj (made by --obj-dir
# from this run): if it no longer does, that file's recipe is stale.
string(JSON in_plane GET "${json}" coupling 3 in_plane)
string(JSON jig GET "${json}" coupling 3 next_jig_x_m)
string(JSON knot GET "${json}" coupling 3 knot)
if(NOT in_plane OR NOT knot STREQUAL "slip")
  message(FATAL_ERROR "coupling[3]: in_plane ${in_plane}, next jig ${jig} m, knot '${knot}' "
                      "(expected a slip knot, the recipe of assets/knots/tied_slip.obj)")
endif()
# The in-plane compliance: the annulus error falls from level 5 to 6 and is within 4 % at 6
# (the fem test's bound), and each level's build is timed.
string(JSON n LENGTH "${json}" in_plane)
if(NOT n EQUAL 2)
  message(FATAL_ERROR "expected 2 in-plane levels, got ${n}")
endif()
string(JSON e5 GET "${json}" in_plane 0 annulus_error)
string(JSON e6 GET "${json}" in_plane 1 annulus_error)
if(NOT e6 LESS e5 OR e6 GREATER 0.04)
  message(FATAL_ERROR "in-plane annulus error: level 5 ${e5}, level 6 ${e6}")
endif()
foreach(i 0 1)
  string(JSON ms GET "${json}" in_plane ${i} stitch_ms)
  if(NOT ms GREATER 0)
    message(FATAL_ERROR "in_plane[${i}].stitch_ms ${ms}")
  endif()
endforeach()
