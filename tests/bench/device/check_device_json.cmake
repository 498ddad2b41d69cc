# Runs microdex-bench device briefly with one other station and checks the JSON's fields.
execute_process(COMMAND ${BENCH} device --duration 2 --others 1 --domain 92 --json ${JSON}
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "microdex-bench device exited with ${rc}")
endif()
file(READ ${JSON} text)
# The hops: the station's stamps (MICRODEX_DEVICE_HOPS) joined with the driver's.
foreach(path "round_trip_us;p50" "round_trip_us;p99" "lost" "sent" "station_cpu"
             "hops_p50_us;to_listener" "hops_p50_us;tick" "hops_p50_us;to_driver")
  string(JSON value ERROR_VARIABLE err GET "${text}" ${path})
  if(err OR "${value}" STREQUAL "")
    message(FATAL_ERROR "${JSON}: ${path} missing (${err})")
  endif()
endforeach()
string(JSON sent GET "${text}" sent)
if(sent LESS 1000)
  message(FATAL_ERROR "${JSON}: only ${sent} samples sent in 2 s")
endif()
# The station answered: most samples came back as forces.
string(JSON forces GET "${text}" forces)
math(EXPR half "${sent} / 2")
if(forces LESS half)
  message(FATAL_ERROR "${JSON}: ${forces} forces for ${sent} samples")
endif()
# Each hop is a duration: positive, and the force is computed within a period.
string(JSON tick GET "${text}" hops_p50_us tick)
if(NOT tick GREATER 0 OR tick GREATER 1000)
  message(FATAL_ERROR "${JSON}: hop tick ${tick} us")
endif()
